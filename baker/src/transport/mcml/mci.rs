//! MCML input files (`.mci`): what both formats share. The run they describe (converted to
//! mm), the data-line reader, number and count parsing, the bounds, and where a run's output
//! file goes. [`super::mci1`] reads MCML 1.x files (`1.0`), [`super::mci2`] MCML 2.0 files
//! (`mcmli2.0`); [`super::parse_mci`] picks by the version line.

use std::path::{Component, Path, PathBuf};

use crate::transport::engine::ROULETTE_WEIGHT;
use crate::transport::stack::{Layer, RadialGrid, Stack};

/// One run of an `.mci` file.
#[derive(Debug, Clone, PartialEq)]
pub struct McmlRun {
    /// The output file name as the file gives it: a relative path (see [`resolve_output`]).
    pub output_file: String,
    pub photons: u64,
    pub dz_cm: f64,
    pub dr_cm: f64,
    pub nz: usize,
    pub nr: usize,
    pub na: usize,
    /// MCML 2.0's roulette threshold weight (MCML 1.x: its constant WEIGHT, 1e-4). The engine
    /// plays roulette at [`ROULETTE_WEIGHT`]; roulette is unbiased at any threshold, so a
    /// different value changes the noise, not the expected answers.
    pub threshold_weight: f64,
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
            threshold_weight: ROULETTE_WEIGHT,
            stack: stack.clone(),
        }
    }
}

/// Largest nz·nr (A(r, z)) and nr·na (Rd(r, α)) grid an .mci file may ask for: 2²⁴ cells
/// (128 MiB of f64 each), far above MCML's examples (nz·nr = 40,000).
pub const MAX_GRID_CELLS: usize = 1 << 24;

/// Most runs one .mci file may hold (MCML 2.0 counts them in a `short`).
pub const MAX_RUNS: usize = 1000;

/// The data lines of an MCML file, in order: blank lines and `#` comment lines skipped
/// (MCML's CommentLineQ: only spaces or tabs before `#` or the end of the line), `\r` treated
/// as blank, text after the values ignored (MCML's FindDataLine).
pub(super) struct DataLines<'a> {
    lines: std::iter::Peekable<std::vec::IntoIter<Line<'a>>>,
}

/// A data line: its 1-based line number in the file and its text.
pub(super) type Line<'a> = (usize, &'a str);

impl<'a> DataLines<'a> {
    pub(super) fn new(text: &'a str) -> Self {
        let lines: Vec<Line<'a>> = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim_end_matches('\r').trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
            .collect();
        Self {
            lines: lines.into_iter().peekable(),
        }
    }

    /// The next data line, which holds `what`.
    pub(super) fn next(&mut self, what: &str) -> Result<Line<'a>, String> {
        self.lines
            .next()
            .ok_or_else(|| format!("file ends before the {what}"))
    }

    /// The next data line without taking it.
    pub(super) fn peek(&mut self) -> Option<Line<'a>> {
        self.lines.peek().copied()
    }

    /// The first number of the next data line, a count (`what`).
    pub(super) fn count(&mut self, what: &str) -> Result<usize, String> {
        let l = self.next(what)?;
        count(nums(l, 1, &format!("the {what}"))?[0], l.0, what)
    }
}

/// The first `n` numbers of a data line (`what` names them in messages).
pub(super) fn nums((line, l): Line<'_>, n: usize, what: &str) -> Result<Vec<f64>, String> {
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

/// `v` as a positive whole number (at most 10¹⁵).
pub(super) fn count(v: f64, line: usize, what: &str) -> Result<usize, String> {
    if v >= 1.0 && v.fract() == 0.0 && v <= 1e15 {
        Ok(v as usize)
    } else {
        Err(format!(
            "line {line}: {what} must be a positive whole number (1 to 1e15), found {v}"
        ))
    }
}

/// nz, nr, na of line `line`, bounded by [`MAX_GRID_CELLS`] before the A(r, z) and Rd(r, α)
/// grids are allocated from them.
/// Run `index`'s stack from what either MCML version reads: the media above and below, the
/// layers (mm) and the radial grid (`dr` in cm, as MCML writes it), checked as a stack file is.
pub(super) fn run_stack(
    index: usize,
    (n_above, layers, n_below): (f64, Vec<Layer>, f64),
    dr_cm: f64,
    nr: usize,
) -> Result<Stack, String> {
    let stack = Stack {
        n_above,
        n_below,
        layers,
        junction: None,
        grid: RadialGrid {
            dr_mm: dr_cm * 10.0,
            nr,
        },
    };
    stack.validate().map_err(|e| format!("run {index}: {e}"))?;
    Ok(stack)
}

pub(super) fn check_grid(line: usize, nz: usize, nr: usize, na: usize) -> Result<(), String> {
    if nz.saturating_mul(nr) > MAX_GRID_CELLS || nr.saturating_mul(na) > MAX_GRID_CELLS {
        return Err(format!(
            "line {line}: nz × nr = {} or nr × na = {} is over {MAX_GRID_CELLS} grid cells",
            nz.saturating_mul(nr),
            nr.saturating_mul(na)
        ));
    }
    Ok(())
}

/// The output file name of a run (the first word of the line), checked by
/// [`check_output_name`].
pub(super) fn output_file_name((line, l): Line<'_>) -> Result<String, String> {
    let name = l
        .split_whitespace()
        .next()
        .ok_or(format!("line {line}: missing output file name"))?;
    check_output_name(name).map_err(|e| format!("line {line}: {e}"))?;
    Ok(name.to_string())
}

/// An output file name must be a relative path that stays where it is resolved
/// ([`resolve_output`]): no root, no `..`, no `\` (a Windows separator here would be part of
/// a file name), no control characters, and a file name at its end.
pub fn check_output_name(name: &str) -> Result<(), String> {
    let p = Path::new(name);
    let bad_char = name.contains('\\') || name.chars().any(char::is_control);
    let escapes = p
        .components()
        .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir));
    let ends_in_name =
        matches!(p.components().next_back(), Some(Component::Normal(_))) && !name.ends_with('/');
    if bad_char || escapes || !ends_in_name {
        return Err(format!(
            "output file {name:?} must be a relative file path inside the output folder (the \
             current directory, or -o DIR): no leading /, no .., no \\ or control characters"
        ));
    }
    Ok(())
}

/// Where a run's output file `name` (from the .mci file) is written. As MCML does, the name
/// is relative to the current directory; with `-o DIR` (`out_dir`) it is relative to DIR
/// instead. Either way nothing is written outside that folder: names that would leave it
/// (absolute paths, `..`) are refused.
pub fn resolve_output(name: &str, out_dir: Option<&Path>) -> Result<PathBuf, String> {
    check_output_name(name)?;
    Ok(match out_dir {
        Some(d) => d.join(name),
        None => PathBuf::from(name),
    })
}
