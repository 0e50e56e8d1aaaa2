//! The checking helpers both spec kinds share: a collector of errors located at
//! file:line:column ([`Ctx`]), range, whole-number and choice checks that record what a field
//! allows, duplicate names, and numbers as messages print them.

use std::collections::HashMap;

use super::error::{SpecError, SpecErrors};
use super::yaml::Spanned;

/// The errors found so far in one spec, each located in `file`.
#[derive(Default)]
pub(super) struct Ctx {
    pub(super) file: String,
    pub(super) errors: Vec<SpecError>,
}

/// The range a number of a spec must lie in, as the resolver checks it and the JSON Schema
/// states it ([`super::schema`]): [lo, hi], or (lo, hi] with `open_lo`; `whole`: a count.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    pub lo: f64,
    pub hi: f64,
    pub open_lo: bool,
    pub whole: bool,
}

impl Bounds {
    /// [lo, hi].
    pub const fn closed(lo: f64, hi: f64) -> Bounds {
        Bounds {
            lo,
            hi,
            open_lo: false,
            whole: false,
        }
    }

    /// (lo, hi]: the lower bound excluded.
    pub const fn above(lo: f64, hi: f64) -> Bounds {
        Bounds {
            open_lo: true,
            ..Bounds::closed(lo, hi)
        }
    }

    /// A whole number in [lo, hi].
    pub const fn whole(lo: f64, hi: f64) -> Bounds {
        Bounds {
            whole: true,
            ..Bounds::closed(lo, hi)
        }
    }
}

/// Line and column of a value.
pub(super) fn loc<T>(s: &Spanned<T>) -> (u64, u64) {
    (s.referenced.line(), s.referenced.column())
}

/// A number as a person reads it in a message: `0.5`, `400`, `1e-9`, `1e300`, `NaN`
/// (Rust's `{}` would print `1e-300` with 300 zeros).
pub fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A range bound as people write it: `1`, `64`, `1e12`, `9.007199254740992e15`.
pub(super) fn bound(x: f64) -> String {
    if x.abs() >= 1e6 {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

/// `n` with thousands separators (`400,000,000,001`), for counts in messages.
pub fn count_text(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// The message for a name equal to an earlier one (`first`, on `first_line`), or equal but for
/// case (one file on macOS and Windows file systems).
pub(super) fn duplicate_message(name: &str, first: &str, first_line: u64) -> String {
    if first == name {
        format!("{name:?} already defined on line {first_line}")
    } else {
        format!(
            "{name:?} differs from {first:?} (line {first_line}) only in case; allowed: names \
             that differ in more than case (they name files, and macOS and Windows file \
             systems ignore case)"
        )
    }
}

/// What a message says about `what` over limit `name` (of `limit`): the limit, and how to
/// raise it.
pub(super) fn over_limit_message(what: &str, name: &str, limit: &str) -> String {
    format!(
        "{what}, over the limit of {limit} (`limits.{name}`); ask for less, or raise \
         `limits.{name}` in the spec if you mean it"
    )
}

impl Ctx {
    pub(super) fn new(file: &str) -> Ctx {
        Ctx {
            file: file.to_string(),
            errors: Vec::new(),
        }
    }

    /// `value`, or every error found.
    pub(super) fn finish<T>(&mut self, value: T) -> Result<T, SpecErrors> {
        if self.errors.is_empty() {
            Ok(value)
        } else {
            Err(SpecErrors(std::mem::take(&mut self.errors)))
        }
    }

    /// Drops repeats of an error (one per point of a sweep), keeping the first of each.
    pub(super) fn dedup(&mut self) {
        let mut seen = Vec::new();
        self.errors.retain(|e| {
            let new = !seen.contains(e);
            if new {
                seen.push(e.clone());
            }
            new
        });
    }

    pub(super) fn invalid(&mut self, at: (u64, u64), field: &str, message: impl Into<String>) {
        self.errors.push(SpecError::Invalid {
            file: self.file.clone(),
            line: at.0,
            column: at.1,
            field: field.to_string(),
            message: message.into(),
        });
    }

    pub(super) fn out_of_range(
        &mut self,
        at: (u64, u64),
        field: &str,
        value: String,
        allowed: String,
    ) {
        self.errors.push(SpecError::OutOfRange {
            file: self.file.clone(),
            line: at.0,
            column: at.1,
            field: field.to_string(),
            value,
            allowed,
        });
    }

    /// `version:` of either kind: 1 today.
    pub(super) fn version(&mut self, v: &Option<Spanned<u32>>) {
        if let Some(v) = v {
            if v.value != 1 {
                self.out_of_range(loc(v), "version", v.value.to_string(), "1".into());
            }
        }
    }

    /// `v` within [lo, hi] (`open_lo`: lo excluded); records an error otherwise.
    pub(super) fn in_range(
        &mut self,
        field: &str,
        v: &Spanned<f64>,
        lo: f64,
        hi: f64,
        open_lo: bool,
    ) -> Option<f64> {
        let x = v.value;
        let ok = x.is_finite() && (if open_lo { x > lo } else { x >= lo }) && x <= hi;
        if ok {
            Some(x)
        } else {
            let allowed = format!(
                "{}{}, {}]",
                if open_lo { "(" } else { "[" },
                num(lo),
                num(hi)
            );
            self.out_of_range(loc(v), field, num(x), allowed);
            None
        }
    }

    /// [`Ctx::in_range`] within `b`.
    pub(super) fn in_bounds(&mut self, field: &str, v: &Spanned<f64>, b: Bounds) -> Option<f64> {
        self.in_range(field, v, b.lo, b.hi, b.open_lo)
    }

    /// [`Ctx::opt_range`] within `b`.
    pub(super) fn opt_bounds(
        &mut self,
        field: &str,
        v: &Option<Spanned<f64>>,
        b: Bounds,
        default: f64,
    ) -> f64 {
        self.opt_range(field, v, b.lo, b.hi, b.open_lo, default)
    }

    /// [`Ctx::in_range`] of an optional value; `default` when it is absent or out of range.
    pub(super) fn opt_range(
        &mut self,
        field: &str,
        v: &Option<Spanned<f64>>,
        lo: f64,
        hi: f64,
        open_lo: bool,
        default: f64,
    ) -> f64 {
        match v {
            Some(s) => self.in_range(field, s, lo, hi, open_lo).unwrap_or(default),
            None => default,
        }
    }

    /// An optional whole number in [lo, hi]: out of range is reported as such, a fraction as
    /// "not a whole number" (the `limits:` and `profiles:` counts).
    pub(super) fn whole(
        &mut self,
        field: &str,
        v: &Option<Spanned<f64>>,
        lo: f64,
        hi: f64,
    ) -> Option<u64> {
        let v = v.as_ref()?;
        let x = self.in_range(field, v, lo, hi, false)?;
        if x.fract() != 0.0 {
            self.invalid(loc(v), field, format!("{x} is not a whole number"));
            return None;
        }
        Some(x as u64)
    }

    /// A whole number in [lo, hi] (the range printed is the one checked), `default` when it
    /// is absent or wrong (the `fibers:` and `bake:` counts).
    pub(super) fn count(
        &mut self,
        field: &str,
        v: &Option<Spanned<f64>>,
        lo: f64,
        hi: f64,
        default: u64,
    ) -> u64 {
        match v {
            Some(s) if !(s.value.fract() == 0.0 && s.value >= lo && s.value <= hi) => {
                self.out_of_range(
                    loc(s),
                    field,
                    num(s.value),
                    format!("[{}, {}], a whole number", bound(lo), bound(hi)),
                );
                default
            }
            _ => self.opt_range(field, v, lo, hi, false, default as f64) as u64,
        }
    }

    /// The option named by `v`; an error listing every option otherwise.
    pub(super) fn choice<T: Copy>(
        &mut self,
        field: &str,
        v: &Spanned<String>,
        options: &[(&str, T)],
    ) -> Option<T> {
        if let Some((_, t)) = options.iter().find(|(k, _)| *k == v.value) {
            return Some(*t);
        }
        let allowed: Vec<&str> = options.iter().map(|o| o.0).collect();
        self.unknown_name(field, v, &allowed, "");
        None
    }

    /// [`Self::choice`] of an optional field: `default` when absent or not one of `options`
    /// (the error is recorded).
    pub(super) fn opt_choice<T: Copy>(
        &mut self,
        field: &str,
        v: &Option<Spanned<String>>,
        options: &[(&str, T)],
        default: T,
    ) -> T {
        v.as_ref()
            .and_then(|v| self.choice(field, v, options))
            .unwrap_or(default)
    }

    /// Records that `v` is none of `allowed`: the nearest names ([`crate::suggest`]) and the
    /// list when it is short or `listed_by` is empty (a choice of the spec language), else its
    /// length and `listed_by` (where to see it).
    pub(super) fn unknown_name(
        &mut self,
        field: &str,
        v: &Spanned<String>,
        allowed: &[&str],
        listed_by: &str,
    ) {
        let advice = if allowed.len() <= crate::suggest::LIST_AT_MOST || listed_by.is_empty() {
            format!(
                "one of {}{}",
                allowed.join(", "),
                crate::suggest::suffix(&v.value, allowed)
            )
        } else {
            crate::suggest::advice(&v.value, allowed, "names", listed_by)
        };
        self.out_of_range(loc(v), field, format!("{:?}", v.value), advice);
    }

    /// Records that `what` (computed from the value at `at`) is over limit `name`.
    pub(super) fn over_limit(
        &mut self,
        at: (u64, u64),
        field: &str,
        what: String,
        name: &str,
        limit: String,
    ) {
        self.invalid(at, field, over_limit_message(&what, name, &limit));
    }

    /// Two entries with one name, or names equal but for case (one file on macOS and
    /// Windows file systems).
    pub(super) fn reject_duplicate_names<'a>(
        &mut self,
        field: &str,
        names: impl Iterator<Item = (&'a str, u64)>,
    ) {
        let mut seen: HashMap<String, (&'a str, u64)> = HashMap::new();
        let mut dups = Vec::new();
        for (name, line) in names {
            let key = name.to_ascii_lowercase();
            if let Some(&(first, first_line)) = seen.get(&key) {
                dups.push(((line, 1), duplicate_message(name, first, first_line)));
            } else {
                seen.insert(key, (name, line));
            }
        }
        for (at, m) in dups {
            self.invalid(at, field, m);
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn counts_read_well() {
        assert_eq!(super::count_text(0), "0");
        assert_eq!(super::count_text(999), "999");
        assert_eq!(super::count_text(1000), "1,000");
        assert_eq!(super::count_text(400_000_000_001), "400,000,000,001");
    }
}
