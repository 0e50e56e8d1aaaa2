//! What the channels of a fiber table are: RGB, wavelengths, or neither.

/// What the channels of a table are.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Channels {
    /// `R`, `G`, `B` (linear sRGB, D65).
    Rgb,
    /// Wavelengths in nm (`550nm`, …).
    Spectral(Vec<f64>),
    Other,
}

impl Channels {
    pub(super) fn of(names: &[String]) -> Self {
        if names == ["R", "G", "B"] {
            return Channels::Rgb;
        }
        let nm: Option<Vec<f64>> = names
            .iter()
            .map(|n| n.strip_suffix("nm").and_then(|x| x.trim().parse().ok()))
            .collect();
        match nm {
            Some(l) if !l.is_empty() => Channels::Spectral(l),
            _ => Channels::Other,
        }
    }
}
