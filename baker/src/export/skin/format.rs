//! Numbers and identifiers as the skin documents print them.

use super::SkinFit;

/// `x` rounded to 7 significant digits, printed without exponent (f64 `Display`).
pub(super) fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let scale = 10f64.powi(6 - x.abs().log10().floor() as i32);
    let r = (x * scale).round() / scale;
    format!("{r}")
}

pub(super) fn nums(v: &[f64]) -> String {
    nums_sep(v, ", ")
}

pub(super) fn nums_sep(v: &[f64], sep: &str) -> String {
    v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(sep)
}

/// `v / max(v)` and `max(v)` (a colour in \[0, 1\] and its multiplier).
pub(super) fn split_max(v: [f64; 3]) -> ([f64; 3], f64) {
    let m = v.iter().copied().fold(0.0, f64::max);
    if m > 0.0 {
        (v.map(|x| x / m), m)
    } else {
        ([0.0; 3], 0.0)
    }
}

/// An identifier for MaterialX and Mitsuba: letters, digits and `_`, not starting with a
/// digit; `.` and other characters become `_`, and a clash gets a numeric suffix.
pub(super) fn identifiers(fits: &[SkinFit]) -> Vec<String> {
    let mut seen = std::collections::BTreeSet::new();
    fits.iter()
        .map(|f| {
            let mut s: String = f
                .name
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect();
            if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
                s.insert(0, '_');
            }
            let mut out = s.clone();
            let mut i = 2;
            while !seen.insert(out.clone()) {
                out = format!("{s}_{i}");
                i += 1;
            }
            out
        })
        .collect()
}
