//! MCML compatibility: read MCML input files (`.mci`) and write MCML's output format
//! (`.mco`, version 1.2.2 layout, Wang, Jacques & Zheng 1995), so the baker can stand in for
//! MCML in existing scripts. MCML works in cm; the engine in mm.

use std::f64::consts::PI;
use std::fmt::Write;
use std::time::Instant;

use super::engine::{run_batches, trace, DirectScorer, McOptions, Prepared, Scorer};
use super::rng::batch_rng;
use super::stack::{Grid, Layer, Stack, MAX_LAYERS};
use super::tally::{McResult, Tally};

/// One run of an `.mci` file.
#[derive(Debug, Clone, PartialEq)]
pub struct McmlRun {
    pub output_file: String,
    pub photons: u64,
    pub dz_cm: f64,
    pub dr_cm: f64,
    pub nz: usize,
    pub nr: usize,
    pub na: usize,
    /// The layers, converted to mm; `grid` is the radial grid of the run.
    pub stack: Stack,
}

impl McmlRun {
    /// MCML grid settings for a stack given in our own format: the stack's radial grid, the
    /// same step in depth down to the last finite boundary (at most 1000 bins), 30 angles.
    pub fn from_stack(stack: &Stack, photons: u64) -> Self {
        let dr_cm = stack.grid.dr_mm / 10.0;
        let depth_mm: f64 = stack
            .layers
            .iter()
            .map(|l| l.d_mm)
            .filter(|d| d.is_finite())
            .sum::<f64>()
            .max(stack.grid.dr_mm);
        Self {
            output_file: "baker.mco".into(),
            photons,
            dz_cm: dr_cm,
            dr_cm,
            nz: ((depth_mm / stack.grid.dr_mm).ceil() as usize).clamp(1, 1000),
            nr: stack.grid.nr,
            na: 30,
            stack: stack.clone(),
        }
    }
}

/// Data lines of an MCML file: blank lines and `#` comments skipped, `\r` treated as blank,
/// text after the values ignored (MCML's FindDataLine).
fn data_lines(text: &str) -> Vec<(usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r').trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
        .collect()
}

/// Parses every run of an `.mci` file (format version 1.0).
/// Largest nz·nr (A(r, z)) and nr·na (Rd(r, α)) grid an .mci file may ask for: 2²⁴ cells
/// (128 MiB of f64 each), far above MCML's examples (nz·nr = 40,000).
pub const MAX_GRID_CELLS: usize = 1 << 24;

pub fn parse_mci(text: &str) -> Result<Vec<McmlRun>, String> {
    let lines = data_lines(text);
    let mut it = lines.into_iter();
    let mut next = |what: &str| {
        it.next()
            .ok_or_else(|| format!("file ends before the {what}"))
    };
    let nums = |(line, l): (usize, &str), n: usize, what: &str| -> Result<Vec<f64>, String> {
        let v: Vec<f64> = l
            .split_whitespace()
            .take(n)
            .map(|t| t.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("line {line}: expected {n} number(s) for {what}, found {l:?}"))?;
        if v.len() < n {
            return Err(format!(
                "line {line}: expected {n} number(s) for {what}, found {l:?}"
            ));
        }
        Ok(v)
    };
    let count = |v: f64, line: usize, what: &str| -> Result<usize, String> {
        if v >= 1.0 && v.fract() == 0.0 && v <= 1e15 {
            Ok(v as usize)
        } else {
            Err(format!(
                "line {line}: {what} must be a positive whole number, found {v}"
            ))
        }
    };
    let _version = next("file version")?;
    let l = next("number of runs")?;
    let runs = count(nums(l, 1, "the number of runs")?[0], l.0, "number of runs")?;
    let mut out = Vec::new();
    for _ in 0..runs {
        let (line, l) = next("output file name")?;
        let output_file = l
            .split_whitespace()
            .next()
            .ok_or(format!("line {line}: missing output file name"))?
            .to_string();
        // Written next to the .mci file: a plain name, never a path that leads elsewhere.
        if output_file == "."
            || output_file == ".."
            || output_file.contains(['/', '\\', '\0'])
            || output_file.chars().any(char::is_control)
        {
            return Err(format!(
                "line {line}: output file {output_file:?} must be a plain file name (it is \
                 written next to the .mci file)"
            ));
        }
        let l = next("number of photons")?;
        let photons = count(
            nums(l, 1, "the number of photons")?[0],
            l.0,
            "number of photons",
        )? as u64;
        let l = next("dz, dr")?;
        let d = nums(l, 2, "dz dr [cm]")?;
        if !(d[0] > 0.0 && d[1] > 0.0) {
            return Err(format!("line {}: dz and dr must be > 0", l.0));
        }
        let l = next("nz, nr, na")?;
        let g = nums(l, 3, "nz nr na")?;
        let (nz, nr, na) = (
            count(g[0], l.0, "nz")?,
            count(g[1], l.0, "nr")?,
            count(g[2], l.0, "na")?,
        );
        // The A(r, z) and Rd(r, α) grids are allocated from these: bounded first.
        if nz.saturating_mul(nr) > MAX_GRID_CELLS || nr.saturating_mul(na) > MAX_GRID_CELLS {
            return Err(format!(
                "line {}: nz × nr = {} or nr × na = {} is over {MAX_GRID_CELLS} grid cells",
                l.0,
                nz.saturating_mul(nr),
                nr.saturating_mul(na)
            ));
        }
        let l = next("number of layers")?;
        let nl = count(
            nums(l, 1, "the number of layers")?[0],
            l.0,
            "number of layers",
        )?;
        if nl > MAX_LAYERS {
            return Err(format!(
                "line {}: at most {MAX_LAYERS} layers are supported",
                l.0
            ));
        }
        let n_above = nums(next("n of the medium above")?, 1, "n above")?[0];
        let mut layers = Vec::new();
        for i in 0..nl {
            let l = next("layer line")?;
            let v = nums(l, 5, "a layer (n mua mus g d)")?;
            layers.push(Layer {
                name: format!("layer {}", i + 1),
                d_mm: v[4] * 10.0,
                eta: v[0],
                mua_per_mm: v[1] / 10.0,
                mus_per_mm: v[2] / 10.0,
                g: v[3],
            });
        }
        let n_below = nums(next("n of the medium below")?, 1, "n below")?[0];
        let stack = Stack {
            n_above,
            n_below,
            layers,
            junction: None,
            grid: Grid {
                dr_mm: d[1] * 10.0,
                nr,
            },
        };
        stack
            .validate()
            .map_err(|e| format!("run {}: {e}", out.len() + 1))?;
        out.push(McmlRun {
            output_file,
            photons,
            dz_cm: d[0],
            dr_cm: d[1],
            nz,
            nr,
            na,
            stack,
        });
    }
    Ok(out)
}

/// MCML's raw 2D tallies (photon weight), clamped into the last bins as MCML does.
#[derive(Debug, Clone, PartialEq)]
pub struct McmlGrid {
    pub a_rz: Vec<f64>,
    pub rd_ra: Vec<f64>,
    pub tt_ra: Vec<f64>,
}

struct GridScorer<'a> {
    direct: DirectScorer<'a>,
    grid: McmlGrid,
    nz: usize,
    nr: usize,
    na: usize,
    dz_mm: f64,
    dr_mm: f64,
    da: f64,
}

impl GridScorer<'_> {
    fn ir(&self, pos: &[f64; 3]) -> usize {
        (((pos[0] * pos[0] + pos[1] * pos[1]).sqrt() / self.dr_mm) as usize).min(self.nr - 1)
    }
    fn ia(&self, cos_out: f64) -> usize {
        ((cos_out.abs().min(1.0).acos() / self.da) as usize).min(self.na - 1)
    }
}

impl Scorer for GridScorer<'_> {
    fn absorb(&mut self, layer: usize, dw: f64, pos: &[f64; 3]) {
        self.direct.absorb(layer, dw, pos);
        let iz = ((pos[2] / self.dz_mm) as usize).min(self.nz - 1);
        let ir = self.ir(pos);
        self.grid.a_rz[ir * self.nz + iz] += dw;
    }
    fn escape(
        &mut self,
        top: bool,
        scattered: bool,
        weight: f64,
        pos: &[f64; 3],
        cos_out: f64,
        path: &[f64],
    ) {
        self.direct
            .escape(top, scattered, weight, pos, cos_out, path);
        let k = self.ir(pos) * self.na + self.ia(cos_out);
        if top {
            self.grid.rd_ra[k] += weight;
        } else {
            self.grid.tt_ra[k] += weight;
        }
    }
    fn lost(&mut self, weight: f64) {
        self.direct.lost(weight);
    }
    fn photon_done(&mut self) {
        self.direct.photon_done();
    }
}

/// Runs `run` with MCML's grids as well as the engine's own tallies.
pub fn simulate_grid(run: &McmlRun, o: &McOptions) -> anyhow::Result<(McResult, McmlGrid)> {
    let p = Prepared::new(&run.stack)?;
    let (nz, nr, na) = (run.nz, run.nr, run.na);
    let empty = || McmlGrid {
        a_rz: vec![0.0; nr * nz],
        rd_ra: vec![0.0; nr * na],
        tt_ra: vec![0.0; nr * na],
    };
    let no_ref = [0.0; MAX_LAYERS];
    let t0 = Instant::now();
    let mut total = Tally::new(p.nl, p.nr);
    let mut grid = empty();
    // Grids can be large (nr·nz values per batch): batches 10× larger than usual amortise
    // their allocation, and only a couple per thread are in flight. Still deterministic for a
    // given seed, whatever the thread count.
    let o = &McOptions {
        batch_size: o.batch_size.max(1) * 10,
        ..o.clone()
    };
    let threads = run_batches(
        2,
        o,
        |b, n| {
            let mut rng = batch_rng(o.seed, b);
            let mut t = Tally::new(p.nl, p.nr);
            let mut events = 0;
            let g = {
                let mut s = GridScorer {
                    direct: DirectScorer {
                        t: &mut t,
                        absorbed: [0.0; MAX_LAYERS],
                        dr_mm: p.dr_mm,
                    },
                    grid: empty(),
                    nz,
                    nr,
                    na,
                    dz_mm: run.dz_cm * 10.0,
                    dr_mm: run.dr_cm * 10.0,
                    da: 0.5 * PI / na as f64,
                };
                for _ in 0..n {
                    trace::<false, _>(&p, &no_ref, &mut rng, &mut s, &mut events);
                }
                s.grid
            };
            t.scattering_events = events;
            (t, g)
        },
        |(t, g)| {
            total.merge(&t);
            for (a, b) in grid.a_rz.iter_mut().zip(&g.a_rz) {
                *a += b;
            }
            for (a, b) in grid.rd_ra.iter_mut().zip(&g.rd_ra) {
                *a += b;
            }
            for (a, b) in grid.tt_ra.iter_mut().zip(&g.tt_ra) {
                *a += b;
            }
        },
    )?;
    let r = McResult::from_tally(&total, p.rsp, p.dr_mm, threads, t0.elapsed().as_secs_f64());
    Ok((r, grid))
}

/// C's `%.<sig>G`: `sig` significant digits, trailing zeros removed, exponent form when the
/// exponent is below −4 or at least `sig`.
fn c_g(x: f64, sig: i32) -> String {
    let exp = if x == 0.0 {
        0
    } else {
        x.abs().log10().floor() as i32
    };
    let trim = |m: &str| -> String {
        if m.contains('.') {
            m.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            m.to_string()
        }
    };
    if !(-5..sig).contains(&exp) {
        let s = format!("{:.*E}", (sig - 1) as usize, x);
        let (m, e) = s.split_once('E').unwrap();
        let e: i32 = e.parse().unwrap();
        format!(
            "{}E{}{:02}",
            trim(m),
            if e < 0 { '-' } else { '+' },
            e.abs()
        )
    } else {
        trim(&format!("{:.*}", (sig - 1 - exp).max(0) as usize, x))
    }
}

/// MCML's `%G`.
fn g6(x: f64) -> String {
    c_g(x, 6)
}

/// C's `%12.4G`.
fn g4(x: f64) -> String {
    format!("{:>12}", c_g(x, 4))
}

/// C's `%12.4E` (two-digit exponent, as glibc prints it).
fn e4(x: f64) -> String {
    let s = format!("{:.4E}", x);
    let (m, e) = s.split_once('E').unwrap();
    let e: i32 = e.parse().unwrap();
    format!(
        "{:>12}",
        format!("{m}E{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
    )
}

/// The `.mco` text of a finished run, scaled as MCML's SumScaleResult does. As in MCML, Rsp is
/// the analytic specular reflectance and Rd everything else that leaves the surface, light
/// reflected back without scattering included. (MCML moves the multiple reflections of a clear
/// first layer into Rsp; here they stay in Rd.)
pub fn write_mco(run: &McmlRun, r: &McResult, g: &McmlGrid) -> String {
    let (nz, nr, na) = (run.nz, run.nr, run.na);
    let (dz, dr) = (run.dz_cm, run.dr_cm);
    let da = 0.5 * PI / na as f64;
    let n = r.photons as f64;
    let mut s = String::new();
    let _ = write!(s, "A1 \t# Version number of the file format.\n\n");
    s.push_str("####\n# Data categories include: \n# InParm, RAT, \n# A_l, A_z, Rd_r, Rd_a, Tt_r, Tt_a, \n# A_rz, Rd_ra, Tt_ra \n####\n\n");
    let _ = write!(
        s,
        "# User time: {:>8.0} sec = {:>8.2} hr.   Simulation time of this run.\n\n",
        r.seconds,
        r.seconds / 3600.0
    );
    s.push_str("InParm \t\t\t# Input parameters. cm is used.\n");
    let _ = writeln!(s, "{} \tA\t\t# output file name, ASCII.", run.output_file);
    let _ = writeln!(s, "{} \t\t\t# No. of photons", r.photons);
    let _ = writeln!(s, "{}\t{}\t\t# dz, dr [cm]", g6(dz), g6(dr));
    let _ = write!(s, "{}\t{}\t{}\t# No. of dz, dr, da.\n\n", nz, nr, na);
    let st = &run.stack;
    let _ = writeln!(s, "{}\t\t\t\t\t# Number of layers", st.layers.len());
    s.push_str("#n\tmua\tmus\tg\td\t# One line for each layer\n");
    let _ = writeln!(s, "{}\t\t\t\t\t# n for medium above", g6(st.n_above));
    for (i, l) in st.layers.iter().enumerate() {
        let d_cm = if l.d_mm.is_finite() {
            l.d_mm / 10.0
        } else {
            1e8
        };
        let _ = writeln!(
            s,
            "{}\t{}\t{}\t{}\t{}\t# layer {}",
            g6(l.eta),
            g6(l.mua_per_mm * 10.0),
            g6(l.mus_per_mm * 10.0),
            g6(l.g),
            g6(d_cm),
            i + 1
        );
    }
    let _ = write!(s, "{}\t\t\t\t\t# n for medium below\n\n", g6(st.n_below));

    // Sums of the raw 2D arrays (MCML: Sum2DRd, Sum2DA, Sum2DTt).
    let rd_r: Vec<f64> = (0..nr)
        .map(|ir| g.rd_ra[ir * na..(ir + 1) * na].iter().sum())
        .collect();
    let tt_r: Vec<f64> = (0..nr)
        .map(|ir| g.tt_ra[ir * na..(ir + 1) * na].iter().sum())
        .collect();
    let rd_a: Vec<f64> = (0..na)
        .map(|ia| (0..nr).map(|ir| g.rd_ra[ir * na + ia]).sum())
        .collect();
    let tt_a: Vec<f64> = (0..na)
        .map(|ia| (0..nr).map(|ir| g.tt_ra[ir * na + ia]).sum())
        .collect();
    let a_z: Vec<f64> = (0..nz)
        .map(|iz| (0..nr).map(|ir| g.a_rz[ir * nz + iz]).sum())
        .collect();
    let z_bounds = st.boundaries_mm();
    let mut a_l = vec![0.0; st.layers.len()];
    for (iz, a) in a_z.iter().enumerate() {
        let zc_mm = (iz as f64 + 0.5) * dz * 10.0;
        let layer = (1..z_bounds.len())
            .find(|&i| zc_mm < z_bounds[i])
            .map_or(st.layers.len() - 1, |i| i - 1);
        a_l[layer] += a;
    }
    s.push_str("RAT #Reflectance, absorption, transmission. \n");
    let rd_total: f64 = rd_r.iter().sum::<f64>() / n;
    let a_total: f64 = a_z.iter().sum::<f64>() / n;
    let tt_total: f64 = tt_r.iter().sum::<f64>() / n;
    let _ = writeln!(s, "{:<14} \t#Specular reflectance [-]", g6(r.rsp));
    let _ = writeln!(s, "{:<14} \t#Diffuse reflectance [-]", g6(rd_total));
    let _ = writeln!(s, "{:<14} \t#Absorbed fraction [-]", g6(a_total));
    let _ = write!(s, "{:<14} \t#Transmittance [-]\n\n", g6(tt_total));
    s.push_str("A_l #Absorption as a function of layer. [-]\n");
    for a in &a_l {
        let _ = writeln!(s, "{}", g4(a / n));
    }
    s.push('\n');
    let ring = |ir: usize| 2.0 * PI * dr * dr * (ir as f64 + 0.5);
    let one_d = |s: &mut String, header: &str, v: &[f64], scale: &dyn Fn(usize) -> f64| {
        s.push_str(header);
        for (i, x) in v.iter().enumerate() {
            let _ = writeln!(s, "{}", e4(x / scale(i)));
        }
        s.push('\n');
    };
    one_d(&mut s, "A_z #A[0], [1],..A[nz-1]. [1/cm]\n", &a_z, &|_| {
        n * dz
    });
    one_d(
        &mut s,
        "Rd_r #Rd[0], [1],..Rd[nr-1]. [1/cm2]\n",
        &rd_r,
        &|ir| n * ring(ir),
    );
    let solid = |ia: usize| n * 2.0 * PI * da * ((ia as f64 + 0.5) * da).sin();
    one_d(
        &mut s,
        "Rd_a #Rd[0], [1],..Rd[na-1]. [sr-1]\n",
        &rd_a,
        &solid,
    );
    one_d(
        &mut s,
        "Tt_r #Tt[0], [1],..Tt[nr-1]. [1/cm2]\n",
        &tt_r,
        &|ir| n * ring(ir),
    );
    one_d(
        &mut s,
        "Tt_a #Tt[0], [1],..Tt[na-1]. [sr-1]\n",
        &tt_a,
        &solid,
    );
    let two_d = |s: &mut String,
                 header: &str,
                 v: &[f64],
                 n2: usize,
                 scale: &dyn Fn(usize, usize) -> f64| {
        s.push_str(header);
        for (k, x) in v.iter().enumerate() {
            s.push_str(&e4(x / scale(k / n2, k % n2)));
            s.push(' ');
            if (k + 1) % 5 == 0 {
                s.push('\n');
            }
        }
        s.push('\n');
    };
    two_d(
        &mut s,
        "# A[r][z]. [1/cm3]\n# A[0][0], [0][1],..[0][nz-1]\n# A[1][0], [1][1],..[1][nz-1]\n# ...\n# A[nr-1][0], [nr-1][1],..[nr-1][nz-1]\nA_rz\n",
        &g.a_rz,
        nz,
        &|ir, _| n * ring(ir) * dz,
    );
    let ra = |ir: usize, ia: usize| {
        n * 4.0
            * PI
            * PI
            * dr
            * dr
            * (da / 2.0).sin()
            * (ir as f64 + 0.5)
            * (2.0 * (ia as f64 + 0.5) * da).sin()
    };
    two_d(
        &mut s,
        "# Rd[r][angle]. [1/(cm2sr)].\n# Rd[0][0], [0][1],..[0][na-1]\n# Rd[1][0], [1][1],..[1][na-1]\n# ...\n# Rd[nr-1][0], [nr-1][1],..[nr-1][na-1]\nRd_ra\n",
        &g.rd_ra,
        na,
        &ra,
    );
    two_d(
        &mut s,
        "# Tt[r][angle]. [1/(cm2sr)].\n# Tt[0][0], [0][1],..[0][na-1]\n# Tt[1][0], [1][1],..[1][na-1]\n# ...\n# Tt[nr-1][0], [nr-1][1],..[nr-1][na-1]\nTt_ra\n",
        &g.tt_ra,
        na,
        &ra,
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn c_formats_match_printf() {
        assert_eq!(g6(0.01), "0.01");
        assert_eq!(g6(1e8), "1E+08");
        assert_eq!(g6(90.0), "90");
        assert_eq!(g6(0.0243729123), "0.0243729");
        assert_eq!(e4(2.799), "  2.7990E+00");
        assert_eq!(e4(0.000123456), "  1.2346E-04");
        assert_eq!(g4(0.26121), "      0.2612");
    }

    #[test]
    fn parses_mcml_template_with_two_runs() {
        let mci = "1.0 # file version\n2 # runs\n\ntemp1.mco A\n10\n20E-4 20E-4\n10 20 30\n2\n# n mua mus g d\n1.0\n1.3 20 200 0.70 0.01\n1.4 10 200 0.90 1.0E+8\n1.0\n\
                   temp2.mco\t A\r\n100\n0.01 0.01\n5 5 5\n1\n1.0\n1.37 1 100 0.9 0.1\n1.0\n";
        let runs = parse_mci(mci).unwrap();
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[0].output_file, "temp1.mco");
        assert_eq!(runs[0].photons, 10);
        assert_eq!((runs[0].nz, runs[0].nr, runs[0].na), (10, 20, 30));
        let l = &runs[0].stack.layers[0];
        assert!(
            (l.d_mm - 0.1).abs() < 1e-12
                && (l.mua_per_mm - 2.0).abs() < 1e-12
                && (l.mus_per_mm - 20.0).abs() < 1e-12
        );
        assert_eq!(runs[1].stack.layers.len(), 1);
    }

    #[test]
    fn reports_the_line_of_a_bad_value() {
        let e = parse_mci("1.0\n1\nout.mco A\nmany\n").unwrap_err();
        assert!(e.contains("line 4"), "{e}");
    }
}
