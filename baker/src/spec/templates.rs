//! Commented starter specs, one per kind, written by `baker init`. Each is a valid spec (a
//! test loads it) that bakes in minutes on 2 cores.

use super::SpecKind;

/// The starter spec of `kind`, as YAML text with comments.
pub fn template(kind: SpecKind) -> &'static str {
    match kind {
        SpecKind::Skin => include_str!("templates/skin.yaml"),
        SpecKind::Fiber => include_str!("templates/fiber.yaml"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_template_is_a_valid_spec_of_its_kind() {
        let dir = tempfile::tempdir().unwrap();
        for (kind, name) in [(SpecKind::Skin, "skin"), (SpecKind::Fiber, "fiber")] {
            let path = dir.path().join(format!("{name}.yaml"));
            std::fs::write(&path, template(kind)).unwrap();
            let spec = crate::spec::load_any(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(spec.kind(), kind, "{name}");
            assert!(
                spec.entries().len() >= 2,
                "{name}: a starter shows several entries"
            );
            crate::spec::budget::check(&spec, &crate::spec::budget::Overrides::none())
                .unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
}
