//! C's printf number formats as MCML's `.mco` files use them (glibc's output).

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
pub(super) fn g6(x: f64) -> String {
    c_g(x, 6)
}

/// C's `%12.4G`.
pub(super) fn g4(x: f64) -> String {
    format!("{:>12}", c_g(x, 4))
}

/// C's `%12.4E` (two-digit exponent, as glibc prints it).
pub(super) fn e4(x: f64) -> String {
    let s = format!("{:.4E}", x);
    let (m, e) = s.split_once('E').unwrap();
    let e: i32 = e.parse().unwrap();
    format!(
        "{:>12}",
        format!("{m}E{}{:02}", if e < 0 { '-' } else { '+' }, e.abs())
    )
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
}
