//! MCML input files (`.mci`, format version 1.0): the runs they describe, converted to mm.

use crate::transport::stack::{Layer, RadialGrid, Stack, MAX_LAYERS};

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

/// Largest nz·nr (A(r, z)) and nr·na (Rd(r, α)) grid an .mci file may ask for: 2²⁴ cells
/// (128 MiB of f64 each), far above MCML's examples (nz·nr = 40,000).
pub const MAX_GRID_CELLS: usize = 1 << 24;

/// The data lines of an MCML file, in order: blank lines and `#` comments skipped, `\r`
/// treated as blank, text after the values ignored (MCML's FindDataLine).
struct DataLines<'a> {
    lines: std::vec::IntoIter<(usize, &'a str)>,
}

/// A data line: its 1-based line number in the file and its text.
type Line<'a> = (usize, &'a str);

impl<'a> DataLines<'a> {
    fn new(text: &'a str) -> Self {
        let lines: Vec<Line<'a>> = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim_end_matches('\r').trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
            .collect();
        Self {
            lines: lines.into_iter(),
        }
    }

    /// The next data line, which holds `what`.
    fn next(&mut self, what: &str) -> Result<Line<'a>, String> {
        self.lines
            .next()
            .ok_or_else(|| format!("file ends before the {what}"))
    }

    /// The first number of the next data line, a count (`what`).
    fn count(&mut self, what: &str) -> Result<usize, String> {
        let l = self.next(what)?;
        count(nums(l, 1, &format!("the {what}"))?[0], l.0, what)
    }
}

/// The first `n` numbers of a data line (`what` names them in messages).
fn nums((line, l): Line<'_>, n: usize, what: &str) -> Result<Vec<f64>, String> {
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
}

/// `v` as a positive whole number.
fn count(v: f64, line: usize, what: &str) -> Result<usize, String> {
    if v >= 1.0 && v.fract() == 0.0 && v <= 1e15 {
        Ok(v as usize)
    } else {
        Err(format!(
            "line {line}: {what} must be a positive whole number, found {v}"
        ))
    }
}

/// Parses every run of an `.mci` file (format version 1.0).
pub fn parse_mci(text: &str) -> Result<Vec<McmlRun>, String> {
    let mut lines = DataLines::new(text);
    let _version = lines.next("file version")?;
    let runs = lines.count("number of runs")?;
    let mut out = Vec::new();
    for _ in 0..runs {
        let run = parse_run(&mut lines, out.len() + 1)?;
        out.push(run);
    }
    Ok(out)
}

/// Run number `index` (1-based): output file, photons, grid, layers.
fn parse_run(lines: &mut DataLines<'_>, index: usize) -> Result<McmlRun, String> {
    let output_file = output_file_name(lines.next("output file name")?)?;
    let photons = lines.count("number of photons")? as u64;
    let l = lines.next("dz, dr")?;
    let d = nums(l, 2, "dz dr [cm]")?;
    if !(d[0] > 0.0 && d[1] > 0.0) {
        return Err(format!("line {}: dz and dr must be > 0", l.0));
    }
    let (nz, nr, na) = grid_counts(lines.next("nz, nr, na")?)?;
    let (n_above, layers, n_below) = parse_layers(lines)?;
    let stack = Stack {
        n_above,
        n_below,
        layers,
        junction: None,
        grid: RadialGrid {
            dr_mm: d[1] * 10.0,
            nr,
        },
    };
    stack.validate().map_err(|e| format!("run {index}: {e}"))?;
    Ok(McmlRun {
        output_file,
        photons,
        dz_cm: d[0],
        dr_cm: d[1],
        nz,
        nr,
        na,
        stack,
    })
}

/// The output file name of a run: a plain name, never a path that leads elsewhere (it is
/// written next to the .mci file).
fn output_file_name((line, l): Line<'_>) -> Result<String, String> {
    let output_file = l
        .split_whitespace()
        .next()
        .ok_or(format!("line {line}: missing output file name"))?
        .to_string();
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
    Ok(output_file)
}

/// nz, nr, na, bounded by [`MAX_GRID_CELLS`] before the A(r, z) and Rd(r, α) grids are
/// allocated from them.
fn grid_counts(l: Line<'_>) -> Result<(usize, usize, usize), String> {
    let g = nums(l, 3, "nz nr na")?;
    let (nz, nr, na) = (
        count(g[0], l.0, "nz")?,
        count(g[1], l.0, "nr")?,
        count(g[2], l.0, "na")?,
    );
    if nz.saturating_mul(nr) > MAX_GRID_CELLS || nr.saturating_mul(na) > MAX_GRID_CELLS {
        return Err(format!(
            "line {}: nz × nr = {} or nr × na = {} is over {MAX_GRID_CELLS} grid cells",
            l.0,
            nz.saturating_mul(nr),
            nr.saturating_mul(na)
        ));
    }
    Ok((nz, nr, na))
}

/// The layer block: number of layers, n above, one `n mua mus g d` line per layer (cm,
/// converted to mm), n below.
fn parse_layers(lines: &mut DataLines<'_>) -> Result<(f64, Vec<Layer>, f64), String> {
    let l = lines.next("number of layers")?;
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
    let n_above = nums(lines.next("n of the medium above")?, 1, "n above")?[0];
    let mut layers = Vec::new();
    for i in 0..nl {
        let l = lines.next("layer line")?;
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
    let n_below = nums(lines.next("n of the medium below")?, 1, "n below")?[0];
    Ok((n_above, layers, n_below))
}

#[cfg(test)]
mod tests {
    use super::*;

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
