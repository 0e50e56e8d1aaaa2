//! MCML 2.0 input files (`.mci`, file version `mcmli2.0`), read in the order and with the
//! checks of MCML 2.0's own reader (mcmlio.c: ReadMediumListQ, then per run ReadParam, then
//! EndOfRunsQ; source: github.com/mhjlam/MCML, 2.0.0/src/mcml/mcmlio.c):
//!
//! 1. the media list: `name n mua mus g` lines up to `end` (1/cm);
//! 2. per run: output file name and format (`A`/`B`; MCML 2.0 writes ASCII either way);
//!    the geometry: the medium above (a name), one `medium thickness` line per layer (cm), the
//!    medium below, `end`; the source type (`pencil`/`isotropic`) and the starting z
//!    (cm) with an optional medium name; `dz dr dt` (cm, cm, ps); `nz nr nt na`; the scored
//!    categories (`Rd_r A_z …`, `\` continues on the next line); `photons [hh:mm]`; the
//!    threshold weight; the seed;
//! 3. `end` after the last run.
//!
//! Comments (`#` to the end of a line) and blank lines may appear anywhere. A line is an `end`
//! when its first word is `end` (MCML looks for "end" anywhere in the line, which also ends a
//! list at a medium named, say, `endothelium`).
//!
//! The engine traces a pencil beam entering at the surface, so a run must start its source at
//! z = 0 in the medium above; isotropic sources and buried starts are refused. Time-resolved
//! grids (dt, nt) are read and checked but not scored, the time limit is ignored (the photon
//! count is required), and the seed is read and checked but not used (MCML 2.0 itself seeds its
//! generator with 1 whatever the file says, mcmlmain.c DoOneRun); `baker mc --seed` sets ours.

use super::mci::{check_grid, count, output_file_name, DataLines, Line, McmlRun, MAX_RUNS};
use crate::transport::stack::{Layer, MAX_LAYERS};

/// Most media a media list may name (MCML 2.0 counts them in a `short`).
pub const MAX_MEDIA: usize = 256;

/// The scored data categories MCML 2.0 knows (mcmlio.c ReadRecordQ), matched ignoring case.
const CATEGORIES: [&str; 19] = [
    "Rd_r", "Rd_a", "Rd_ra", "Rd_t", "Rd_rt", "Rd_at", "Rd_rat", "Td_r", "Td_a", "Td_ra", "Td_t",
    "Td_rt", "Td_at", "Td_rat", "A_z", "A_rz", "A_t", "A_zt", "A_rzt",
];

/// One entry of the media list, in the file's units (1/cm).
#[derive(Debug, Clone)]
struct Medium<'a> {
    name: &'a str,
    n: f64,
    mua_per_cm: f64,
    mus_per_cm: f64,
    g: f64,
}

/// The words of a data line before its comment.
fn words(l: &str) -> impl Iterator<Item = &str> {
    l.split('#').next().unwrap_or("").split_whitespace()
}

fn is_end((_, l): Line<'_>) -> bool {
    words(l).next() == Some("end")
}

/// Word `i` of line `l` as a number (`what` names it in messages).
fn number((line, l): Line<'_>, i: usize, what: &str) -> Result<f64, String> {
    let w = words(l)
        .nth(i)
        .ok_or_else(|| format!("line {line}: missing {what} in {l:?}"))?;
    w.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("line {line}: {what} must be a number, found {w:?}"))
}

/// Every run of a 2.0 file whose version line `lines` has already given.
pub(super) fn parse(lines: &mut DataLines<'_>) -> Result<Vec<McmlRun>, String> {
    let media = parse_media(lines)?;
    let mut runs = Vec::new();
    loop {
        if runs.len() == MAX_RUNS {
            return Err(format!("more than {MAX_RUNS} runs in one file"));
        }
        runs.push(parse_run(lines, &media, runs.len() + 1)?);
        // MCML's EndOfRunsQ: the runs end at a line `end`; the file must not end first.
        match lines.peek() {
            None => return Err("file ends without the `end` after the last run".into()),
            Some(l) if is_end(l) => return Ok(runs),
            Some(_) => {}
        }
    }
}

/// The media list up to its `end`, with MCML's checks (n > 0, mua ≥ 0, mus ≥ 0, −1 ≤ g ≤ 1),
/// at most [`MAX_MEDIA`] media, names unique.
fn parse_media<'a>(lines: &mut DataLines<'a>) -> Result<Vec<Medium<'a>>, String> {
    let mut media: Vec<Medium<'a>> = Vec::new();
    loop {
        let l = lines.next("`end` of the media list")?;
        if is_end(l) {
            break;
        }
        if media.len() == MAX_MEDIA {
            return Err(format!(
                "line {}: more than {MAX_MEDIA} media in the media list",
                l.0
            ));
        }
        let name = words(l.1).next().unwrap_or("");
        let m = Medium {
            name,
            n: number(l, 1, &format!("n of medium {name}"))?,
            mua_per_cm: number(l, 2, &format!("mua [1/cm] of medium {name}"))?,
            mus_per_cm: number(l, 3, &format!("mus [1/cm] of medium {name}"))?,
            g: number(l, 4, &format!("g of medium {name}"))?,
        };
        for (field, v, ok, allowed) in [
            ("n", m.n, m.n > 0.0, "> 0"),
            ("mua", m.mua_per_cm, m.mua_per_cm >= 0.0, ">= 0 [1/cm]"),
            ("mus", m.mus_per_cm, m.mus_per_cm >= 0.0, ">= 0 [1/cm]"),
            ("g", m.g, (-1.0..=1.0).contains(&m.g), "[-1, 1]"),
        ] {
            if !ok {
                return Err(format!(
                    "line {}: medium {name}: {field} = {v} is out of range (allowed {allowed})",
                    l.0
                ));
            }
        }
        if media.iter().any(|o| o.name == name) {
            return Err(format!("line {}: medium {name} is listed twice", l.0));
        }
        media.push(m);
    }
    if media.is_empty() {
        return Err("the media list is empty".into());
    }
    Ok(media)
}

/// Run number `index` (1-based), as MCML 2.0's ReadParam reads it.
fn parse_run(
    lines: &mut DataLines<'_>,
    media: &[Medium<'_>],
    index: usize,
) -> Result<McmlRun, String> {
    let l = lines.next("output file name and format")?;
    let output_file = output_file_name(l)?;
    if words(l.1).nth(1).is_none() {
        return Err(format!(
            "line {}: expected the output file name and its format (A or B), found {:?}",
            l.0, l.1
        ));
    }
    let (n_above, layers, n_below, top) = parse_geometry(lines, media)?;
    parse_source(lines, &top)?;
    let l = lines.next("dz, dr, dt")?;
    let (dz_cm, dr_cm) = (number(l, 0, "dz [cm]")?, number(l, 1, "dr [cm]")?);
    let dt_ps = number(l, 2, "dt [ps]")?;
    if !(dz_cm > 0.0 && dr_cm > 0.0 && dt_ps > 0.0) {
        return Err(format!("line {}: dz, dr and dt must be > 0", l.0));
    }
    let l = lines.next("nz, nr, nt, na")?;
    let mut g = [0; 4];
    for (i, what) in ["nz", "nr", "nt", "na"].iter().enumerate() {
        g[i] = count(number(l, i, what)?, l.0, what)?;
    }
    let [nz, nr, _nt, na] = g;
    check_grid(l.0, nz, nr, na)?;
    parse_categories(lines)?;
    let photons = parse_photons(lines.next("number of photons")?)?;
    let l = lines.next("threshold weight")?;
    let threshold_weight = number(l, 0, "the threshold weight")?;
    if !(0.0..1.0).contains(&threshold_weight) {
        return Err(format!(
            "line {}: threshold weight {threshold_weight} is out of range (allowed [0, 1))",
            l.0
        ));
    }
    parse_seed(lines.next("random number seed")?)?;
    let stack = super::mci::run_stack(index, (n_above, layers, n_below), dr_cm, nr)?;
    Ok(McmlRun {
        output_file,
        photons,
        dz_cm,
        dr_cm,
        nz,
        nr,
        na,
        threshold_weight,
        stack,
    })
}

/// The medium named on line `l`; an error naming the line and the known media otherwise.
fn medium<'m, 'a>(
    media: &'m [Medium<'a>],
    name: &str,
    l: Line<'_>,
) -> Result<&'m Medium<'a>, String> {
    media.iter().find(|m| m.name == name).ok_or_else(|| {
        let known: Vec<&str> = media.iter().map(|m| m.name).collect();
        format!(
            "line {}: unknown medium {name:?} (the media list has {})",
            l.0,
            known.join(", ")
        )
    })
}

/// The geometry up to its `end`: the medium above, the layers (`medium thickness` [cm],
/// converted to mm), the medium below; at most [`MAX_LAYERS`] layers. Returns n above, the
/// layers, n below and the name of the medium above.
fn parse_geometry(
    lines: &mut DataLines<'_>,
    media: &[Medium<'_>],
) -> Result<(f64, Vec<Layer>, f64, String), String> {
    let mut rows: Vec<Line<'_>> = Vec::new();
    loop {
        let l = lines.next("`end` of the layers")?;
        if is_end(l) {
            break;
        }
        if rows.len() == MAX_LAYERS + 2 {
            return Err(format!(
                "line {}: more than {MAX_LAYERS} layers (plus the media above and below)",
                l.0
            ));
        }
        rows.push(l);
    }
    if rows.len() < 3 {
        let at = rows
            .last()
            .map_or(String::new(), |l| format!("line {}: ", l.0));
        return Err(format!(
            "{at}the geometry needs the medium above, at least one layer and the medium below"
        ));
    }
    let name = |l: Line<'_>| words(l.1).next().unwrap_or("").to_string();
    let n_above = medium(media, &name(rows[0]), rows[0])?.n;
    let last = rows[rows.len() - 1];
    let n_below = medium(media, &name(last), last)?.n;
    let mut layers = Vec::new();
    for &l in &rows[1..rows.len() - 1] {
        let m = medium(media, &name(l), l)?;
        let d_cm = number(l, 1, &format!("thickness [cm] of layer {}", m.name))?;
        if d_cm <= 0.0 {
            return Err(format!(
                "line {}: thickness {d_cm} of layer {} must be > 0 [cm]",
                l.0, m.name
            ));
        }
        layers.push(Layer {
            name: m.name.to_string(),
            d_mm: d_cm * 10.0,
            eta: m.n,
            mua_per_mm: m.mua_per_cm / 10.0,
            mus_per_mm: m.mus_per_cm / 10.0,
            g: m.g,
        });
    }
    Ok((n_above, layers, n_below, name(rows[0])))
}

/// The source type and its starting point: only a pencil beam at z = 0 in the medium above
/// (MCML's default, and what the engine traces). `top` names the medium above.
fn parse_source(lines: &mut DataLines<'_>, top: &str) -> Result<(), String> {
    let l = lines.next("source type")?;
    match words(l.1).next() {
        Some("pencil") => {}
        Some("isotropic") => {
            return Err(format!(
                "line {}: isotropic sources are not supported (only pencil)",
                l.0
            ))
        }
        other => {
            return Err(format!(
                "line {}: unknown source type {:?} (allowed: pencil, isotropic)",
                l.0,
                other.unwrap_or("")
            ))
        }
    }
    let l = lines.next("starting z of the source")?;
    let z_cm = number(l, 0, "the starting z [cm] of the source")?;
    let in_medium = words(l.1).nth(1);
    // MCML's ReadStartPQ: z alone, or z with the medium above, starts above the surface; z = 0
    // with the first layer's medium starts inside that layer (no specular reflection), which
    // is not traced here.
    let above = in_medium.is_none_or(|n| n == top);
    if z_cm != 0.0 || !above {
        return Err(format!(
            "line {}: the source must start at z = 0 in the medium above (a pencil beam at the \
             surface); found {:?}",
            l.0, l.1
        ));
    }
    Ok(())
}

/// The scored data categories: known names (any case), `\` continuing on the next data line.
/// The .mco written holds all of MCML 1.x's sections whatever is asked for.
fn parse_categories(lines: &mut DataLines<'_>) -> Result<(), String> {
    let mut l = lines.next("scored data categories")?;
    let mut any = false;
    loop {
        let mut more = false;
        for w in words(l.1) {
            if w.starts_with('\\') {
                more = true;
                break;
            }
            if !CATEGORIES.iter().any(|c| c.eq_ignore_ascii_case(w)) {
                return Err(format!(
                    "line {}: unknown scored category {w:?} (allowed: {})",
                    l.0,
                    CATEGORIES.join(" ")
                ));
            }
            any = true;
        }
        if !more {
            break;
        }
        l = lines.next("scored data categories after `\\`")?;
    }
    if !any {
        return Err(format!("line {}: no scored data category", l.0));
    }
    Ok(())
}

/// `photons [hh:mm]` (MCML's ReadNumPhotonsQ: a float, truncated): the photon count; a time
/// limit alone is refused.
fn parse_photons(l: Line<'_>) -> Result<u64, String> {
    let first = words(l.1).next().unwrap_or("");
    if first.contains(':') {
        return Err(format!(
            "line {}: a time limit alone ({first}) is not supported; give the number of photons",
            l.0
        ));
    }
    let v = number(l, 0, "the number of photons")?;
    Ok(count(v.trunc(), l.0, "number of photons")? as u64)
}

/// The seed: a whole number ≥ 0 (read and checked as MCML does; not used).
fn parse_seed(l: Line<'_>) -> Result<(), String> {
    let w = words(l.1).next().unwrap_or("");
    w.parse::<u64>().map(|_| ()).map_err(|_| {
        format!(
            "line {}: random number seed must be a whole number >= 0, found {w:?}",
            l.0
        )
    })
}
