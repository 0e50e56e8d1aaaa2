//! "Did you mean …?": the one to three known names nearest a name that is not one of them
//! (entry names, spec fields, choices, dyes, export targets), and the advice that follows a
//! miss — never a wall of names.
//!
//! The metric, on the names lowercased:
//!
//! 1. an exact match but for case is the only suggestion;
//! 2. otherwise names of which the given one is a prefix, or that are a prefix of it (the
//!    shorter at least 3 characters), come first;
//! 3. then names whose Jaro–Winkler similarity ([`strsim::jaro_winkler`]) is at least
//!    [`THRESHOLD`] and within [`MARGIN`] of the best such name.
//!
//! Each group is ranked by Jaro–Winkler similarity (ties in the order the names are given);
//! at most [`MOST`] are suggested.

/// Most names suggested.
pub const MOST: usize = 3;
/// Least Jaro–Winkler similarity of a suggestion that is not a prefix match.
pub const THRESHOLD: f64 = 0.8;
/// A suggestion by similarity is at most this much less similar than the best one.
pub const MARGIN: f64 = 0.05;
/// Sets of at most this many names are listed whole after a miss; larger ones are counted.
pub const LIST_AT_MOST: usize = 8;

/// The names of `names` nearest `typo` (at most [`MOST`], best first; empty when none is
/// close).
pub fn nearest<'a, S: AsRef<str> + ?Sized>(typo: &str, names: &'a [&'a S]) -> Vec<&'a str> {
    let t = typo.to_lowercase();
    let lower: Vec<(String, &str)> = names
        .iter()
        .map(|n| (n.as_ref().to_lowercase(), n.as_ref()))
        .collect();
    if let Some((_, n)) = lower.iter().find(|(l, _)| *l == t) {
        return vec![n];
    }
    let prefix = |l: &str| {
        let (short, long) = if l.len() < t.len() {
            (l, t.as_str())
        } else {
            (t.as_str(), l)
        };
        short.chars().count() >= 3 && long.starts_with(short)
    };
    let mut scored: Vec<(bool, f64, &str)> = lower
        .iter()
        .map(|(l, n)| (prefix(l), strsim::jaro_winkler(&t, l), *n))
        .filter(|(p, s, _)| *p || *s >= THRESHOLD)
        .collect();
    // Prefix matches first, then by similarity; a stable sort keeps the given order of ties.
    scored.sort_by(|a, b| b.0.cmp(&a.0).then(b.1.total_cmp(&a.1)));
    let best = scored.iter().find(|s| !s.0).map_or(1.0, |s| s.1);
    let mut out: Vec<&str> = scored
        .into_iter()
        .filter(|(p, s, _)| *p || *s >= best - MARGIN)
        .map(|s| s.2)
        .collect();
    out.dedup();
    out.truncate(MOST);
    out
}

/// `"a"`, `"a" or "b"`, `"a", "b" or "c"`.
fn quoted(names: &[&str]) -> String {
    let q: Vec<String> = names.iter().map(|n| format!("{n:?}")).collect();
    match q.split_last() {
        None => String::new(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

/// `did you mean "a" or "b"?` for the names nearest `typo`; `None` when none is close.
pub fn did_you_mean<S: AsRef<str> + ?Sized>(typo: &str, names: &[&S]) -> Option<String> {
    let near = nearest(typo, names);
    (!near.is_empty()).then(|| format!("did you mean {}?", quoted(&near)))
}

/// `; did you mean "a"?` (the tail of a message that already lists the allowed names), or
/// nothing.
pub fn suffix<S: AsRef<str> + ?Sized>(typo: &str, names: &[&S]) -> String {
    did_you_mean(typo, names).map_or(String::new(), |d| format!("; {d}"))
}

/// What follows a name that is not one of `names` (whose plural is `plural`, e.g.
/// "entries"): the nearest names, then the names themselves when there are at most
/// [`LIST_AT_MOST`], else their count and `listed_by` (where to see them all, e.g.
/// "`baker validate specs/a.yaml` lists them").
///
/// - `did you mean "blender"? allowed: burley, mtlx, blender`
/// - `allowed: burley, mtlx, blender`
/// - `did you mean "typeIII_age30_xi0"? (126 entries; `baker validate F` lists them)`
/// - `none of the 126 entries is close; `baker validate F` lists them`
pub fn advice<S: AsRef<str> + ?Sized>(
    typo: &str,
    names: &[&S],
    plural: &str,
    listed_by: &str,
) -> String {
    let near = did_you_mean(typo, names);
    if names.is_empty() {
        return format!("there are no {plural}");
    }
    if names.len() <= LIST_AT_MOST {
        let all: Vec<&str> = names.iter().map(|n| n.as_ref()).collect();
        let all = format!("allowed: {}", all.join(", "));
        return match near {
            Some(d) => format!("{d} {all}"),
            None => all,
        };
    }
    let n = names.len();
    match near {
        Some(d) => format!("{d} ({n} {plural}; {listed_by})"),
        None => format!("none of the {n} {plural} is close; {listed_by}"),
    }
}

/// `no entry named "x" in PLACE; ` + [`advice`] (plural "entries").
pub fn no_entry<S: AsRef<str> + ?Sized>(
    name: &str,
    place: &str,
    names: &[&S],
    listed_by: &str,
) -> String {
    format!(
        "no entry named {name:?} in {place}; {}",
        advice(name, names, "entries", listed_by)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fitzpatrick() -> Vec<String> {
        let mut v = Vec::new();
        for age in [20, 30, 40, 50, 60, 70, 80] {
            for t in ["I", "II", "III", "IV", "V", "VI"] {
                for xi in ["0", "0.5", "1"] {
                    v.push(format!("type{t}_age{age}_xi{xi}"));
                }
            }
        }
        v
    }

    #[test]
    fn nearest_names_by_case_prefix_and_similarity() {
        let targets = [
            "burley", "mtlx", "blender", "unreal", "unity", "pbrt", "mitsuba",
        ];
        assert_eq!(nearest("blendr", &targets), ["blender"]);
        assert_eq!(nearest("Blender", &targets), ["blender"]);
        assert_eq!(nearest("unr", &targets), ["unreal"]);
        assert_eq!(nearest("povray", &targets), Vec::<&str>::new());
        let names = fitzpatrick();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        assert_eq!(
            nearest("typeIII_age3O", &refs),
            [
                "typeIII_age30_xi0",
                "typeIII_age30_xi1",
                "typeIII_age30_xi0.5"
            ]
        );
        assert_eq!(nearest("typeiii_age30_xi1", &refs), ["typeIII_age30_xi1"]);
        assert!(nearest("xyz", &refs).is_empty());
        let fields = [
            "name",
            "skin_type",
            "skin_type_melanin",
            "melanosome_fraction",
        ];
        // The close one only, not everything above the threshold.
        assert_eq!(nearest("skin_tpye", &fields), ["skin_type"]);
        assert_eq!(nearest("VII", &["I", "II", "III", "IV", "V", "VI"]), ["VI"]);
    }

    #[test]
    fn advice_lists_few_names_and_counts_many() {
        let few = ["chiang", "pbrt", "mitsuba", "blender"];
        assert_eq!(
            advice("blendr", &few, "targets", "-"),
            "did you mean \"blender\"? allowed: chiang, pbrt, mitsuba, blender"
        );
        assert_eq!(
            advice("povray", &few, "targets", "-"),
            "allowed: chiang, pbrt, mitsuba, blender"
        );
        let names = fitzpatrick();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let m = no_entry(
            "typeIII_age3O",
            "f.yaml",
            &refs,
            "`baker validate f.yaml` lists them",
        );
        assert_eq!(
            m,
            "no entry named \"typeIII_age3O\" in f.yaml; did you mean \"typeIII_age30_xi0\", \
             \"typeIII_age30_xi1\" or \"typeIII_age30_xi0.5\"? (126 entries; `baker validate \
             f.yaml` lists them)"
        );
        let m = no_entry("xyz", "f.yaml", &refs, "`baker validate f.yaml` lists them");
        assert_eq!(
            m,
            "no entry named \"xyz\" in f.yaml; none of the 126 entries is close; \
             `baker validate f.yaml` lists them"
        );
        assert!(!m.contains("typeI_age20_xi0"));
        assert_eq!(
            suffix("forarm", &["face", "forearm"]),
            "; did you mean \"forearm\"?"
        );
        assert_eq!(suffix("elbow", &["face", "forearm"]), "");
    }
}
