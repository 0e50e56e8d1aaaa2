//! How long computations report how far they are, without knowing who listens.
//!
//! The physics (transport runs, fiber traces) calls [`Progress::advance`] with the work it has
//! finished; the command line implements the trait with an indicatif bar, and bakes report
//! phases and units through their event stream. Nothing below the CLI names a terminal type.

use std::sync::Arc;

/// A sink for finished work, in the caller's units (photon packets, directions).
pub trait Progress: Send + Sync + std::fmt::Debug {
    /// `n` more units are done.
    fn advance(&self, n: u64);
}

/// A shared progress sink; `None` reports nowhere.
pub type Reporter = Option<Arc<dyn Progress>>;

/// Reports `n` finished units to `r`, if there is one.
pub fn advance(r: &Reporter, n: u64) {
    if let Some(p) = r {
        p.advance(n);
    }
}

/// `x` with an SI prefix and three significant digits, then `unit` (e.g. `3.05 T photons`,
/// `80.3 k photons/s`, `999 photons`); whole numbers below 1000 print as they are.
pub fn si(x: f64, unit: &str) -> String {
    const PREFIXES: [&str; 7] = ["", "k", "M", "G", "T", "P", "E"];
    let sep = if unit.is_empty() { "" } else { " " };
    if !x.is_finite() {
        return format!("{x}{sep}{unit}");
    }
    let (sign, mut v) = (if x < 0.0 { "-" } else { "" }, x.abs());
    let mut p = 0;
    while v >= 999.5 && p + 1 < PREFIXES.len() {
        v /= 1000.0;
        p += 1;
    }
    let digits = if (p == 0 && v.fract() == 0.0) || v >= 99.95 {
        0
    } else if v >= 9.995 {
        1
    } else if v >= 0.9995 || v == 0.0 {
        2
    } else {
        3
    };
    let prefix = PREFIXES[p];
    let (space, sep) = if prefix.is_empty() {
        (sep, "")
    } else {
        (" ", sep)
    };
    format!("{sign}{v:.digits$}{space}{prefix}{sep}{unit}")
}

/// `n` with thousands separators: `3,046,320,000,000`.
pub fn grouped(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::with_capacity(s.len() + s.len() / 3);
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// A duration for people: `0.8 s`, `42 s`, `3 min 20 s`, `2 h 05 min`.
pub fn duration(seconds: f64) -> String {
    if !seconds.is_finite() || seconds < 0.0 {
        return "?".into();
    }
    if seconds < 10.0 {
        return format!("{seconds:.1} s");
    }
    let s = seconds.round() as u64;
    match s {
        0..=59 => format!("{s} s"),
        60..=3599 => format!("{} min {:02} s", s / 60, s % 60),
        _ => format!("{} h {:02} min", s / 3600, (s % 3600) / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn si_prefixes_round_to_three_digits() {
        assert_eq!(si(0.0, "photons"), "0 photons");
        assert_eq!(si(999.0, "photons"), "999 photons");
        assert_eq!(si(1000.0, "photons"), "1.00 k photons");
        assert_eq!(si(1e12, "photons"), "1.00 T photons");
        assert_eq!(si(3_046_320_000_000.0, "photons"), "3.05 T photons");
        assert_eq!(si(80_260.802_5, "photons/s"), "80.3 k photons/s");
        assert_eq!(si(1_234_567.0, "photons/s"), "1.23 M photons/s");
        // Rounding that carries into the next prefix.
        assert_eq!(si(999_999.0, "photons"), "1.00 M photons");
        assert_eq!(si(999.7, "x"), "1.00 k x");
        assert_eq!(si(12.345, "profiles/s"), "12.3 profiles/s");
        assert_eq!(si(0.456, "profiles/s"), "0.456 profiles/s");
        assert_eq!(si(2.5, ""), "2.50");
        assert_eq!(si(-1500.0, "B"), "-1.50 k B");
        assert_eq!(si(2e6, ""), "2.00 M");
        assert_eq!(si(f64::INFINITY, "x"), "inf x");
    }

    #[test]
    fn thousands_and_durations() {
        assert_eq!(grouped(0), "0");
        assert_eq!(grouped(999), "999");
        assert_eq!(grouped(1000), "1,000");
        assert_eq!(grouped(3_046_320_000_000), "3,046,320,000,000");
        assert_eq!(duration(0.84), "0.8 s");
        assert_eq!(duration(42.4), "42 s");
        assert_eq!(duration(200.0), "3 min 20 s");
        assert_eq!(duration(7500.0), "2 h 05 min");
        assert_eq!(duration(f64::NAN), "?");
    }
}
