//! Entry names become file and folder names (`optics/<entry>.csv`, `<entry>/<entry>.h5`), HDF5
//! groups and asset names in engines, so they are names and nothing else:
//!
//! - 1 to [`MAX_NAME_LEN`] characters from `A–Z a–z 0–9 _ - . +` (ASCII: the same bytes on every
//!   file system, no Unicode normalisation differences between macOS and Linux);
//! - starting with a letter, a digit or `_` (no hidden files, `.`, `..`, or names that read as
//!   command-line flags);
//! - no `..` anywhere;
//! - not a device name reserved on Windows (`CON`, `NUL`, `COM1`, … with any extension), where
//!   baked tables are often copied.
//!
//! The resolver checks every entry name and every name a sweep template expands to; the output
//! layer ([`crate::output::paths`]) checks every path again before writing.

/// Longest entry name, characters.
pub const MAX_NAME_LEN: usize = 100;

/// The characters a name may hold, for messages.
pub const ALLOWED: &str = "letters A–Z a–z, digits, `_`, `-`, `.` and `+`, starting with a \
                           letter, digit or `_`, at most 100 characters, no `..`";

/// `Ok` for a valid entry name; otherwise what is wrong with it, in words.
pub fn check(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("is empty".into());
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '+')))
    {
        let what = match c {
            '/' | '\\' => "a path separator".to_string(),
            '\0' => "a NUL character".to_string(),
            c if c.is_control() => format!("a control character (U+{:04X})", c as u32),
            ' ' => "a space".to_string(),
            c => format!("{c:?}"),
        };
        return Err(format!("holds {what}"));
    }
    if name.len() > MAX_NAME_LEN {
        return Err(format!("has {} characters", name.len()));
    }
    if !name.starts_with(|c: char| c.is_ascii_alphanumeric() || c == '_') {
        return Err("starts with a character other than a letter, digit or `_`".into());
    }
    if name.contains("..") {
        return Err("holds `..`".into());
    }
    let stem = name.split('.').next().unwrap_or(name).to_ascii_uppercase();
    let reserved = matches!(stem.as_str(), "CON" | "PRN" | "AUX" | "NUL")
        || (stem.len() == 4
            && (stem.starts_with("COM") || stem.starts_with("LPT"))
            && stem.as_bytes()[3].is_ascii_digit());
    if reserved {
        return Err(format!("is a device name reserved on Windows ({stem})"));
    }
    Ok(())
}

/// The message for a bad name: what is wrong and what is allowed.
pub fn message(name: &str, problem: &str) -> String {
    format!("{name:?} {problem}; allowed: {ALLOWED}")
}

/// The message for `--entry NAME` naming no entry of the spec `file` (entries `names`): the
/// nearest names ([`crate::suggest`]) and, for a long list, its length and the command that
/// lists it, never the whole list.
pub fn unknown_entry(file: &str, name: &str, names: &[&str]) -> String {
    crate::suggest::no_entry(
        name,
        file,
        names,
        &format!("`baker validate {file}` lists them"),
    )
}

/// Checks a spec file's stem, which names its output folder `OUT/<stem>/`. Looser than entry
/// names (the user chose the file name, spaces and Unicode are fine) but never a path trick:
/// not empty, no leading dot (`.cache`, `..`), no separator or control character.
pub fn check_stem(stem: &str) -> Result<(), String> {
    if stem.is_empty() {
        return Err("is empty".into());
    }
    if stem.starts_with('.') {
        return Err("starts with `.` (hidden folders such as `.cache` belong to the baker)".into());
    }
    if stem.contains(['/', '\\']) || stem.chars().any(char::is_control) {
        return Err("holds a path separator or a control character".into());
    }
    if stem.len() > 200 {
        return Err(format!("has {} bytes (at most 200)", stem.len()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_names() {
        for ok in [
            "a",
            "fitz_II_25",
            "wool-1.5+dye",
            "_x",
            "9",
            "con_x",
            "COM",
            "lpt",
        ] {
            assert_eq!(check(ok), Ok(()), "{ok}");
        }
        let long = "a".repeat(101);
        for bad in [
            "", "..", ".", ".hidden", "../../x", "/abs/x", "a/b", "a\\b", "a\0b", "a..b", "-x",
            "a b", "é", "nul", "NUL.csv", "com1", "Lpt9.h5", "a\nb", &long,
        ] {
            assert!(check(bad).is_err(), "{bad:?}");
        }
        assert_eq!(check("a/b").unwrap_err(), "holds a path separator");
        assert!(check_stem("my spec").is_ok());
        for bad in ["", ".cache", "..", "a/b", "a\u{7}"] {
            assert!(check_stem(bad).is_err(), "{bad:?}");
        }
    }
}
