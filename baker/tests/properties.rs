//! Property tests over the whole valid parameter space of the skin model.

use baker::skin::{
    self, BodyLocation, Gender, HypodermisAbsorption, MelaninInput, ModelKind,
    PheomelaninAbsorption, SkinParams, SkinType,
};
use baker::spectral::WavelengthGrid;
use proptest::prelude::*;

fn any_params() -> impl Strategy<Value = SkinParams> {
    let people = (
        18.0..=90.0f64,
        prop_oneof![Just(Gender::Female), Just(Gender::Male)],
        prop_oneof![
            Just(BodyLocation::Face),
            Just(BodyLocation::Forearm),
            Just(BodyLocation::BackOfHand),
            Just(BodyLocation::Palm)
        ],
        prop_oneof![
            (0usize..6).prop_map(|i| MelaninInput::SkinType(SkinType::ALL[i])),
            (0.0..=0.5f64).prop_map(MelaninInput::MelanosomeFraction)
        ],
        0.0..=1.0f64,
    );
    let blood = (
        0.001..=0.2f64,
        0.001..=0.2f64,
        0.0..=0.2f64,
        0.0..=1.0f64,
        1.0..=300.0f64,
    );
    let options = (
        prop_oneof![Just(ModelKind::FiveLayer), Just(ModelKind::ThreeLayer)],
        prop_oneof![
            Just(HypodermisAbsorption::Blood),
            Just(HypodermisAbsorption::WaterOnly)
        ],
        prop_oneof![
            Just(PheomelaninAbsorption::ThesisFit),
            Just(PheomelaninAbsorption::Measured)
        ],
        proptest::array::uniform5(0.0..=0.95f64),
    );
    (people, blood, options).prop_map(
        |((age, g, loc, mel, xi), (pd, rd, hd, s, hb), (model, hyp, ph, water))| {
            let mut p = SkinParams::new(age, g, loc, mel, xi);
            p.blood_fraction_pd = pd;
            p.blood_fraction_rd = rd;
            p.blood_fraction_hd = hd;
            p.oxygen_saturation = s;
            p.hemoglobin_g_per_l = hb;
            p.model = model;
            p.hypodermis_absorption = hyp;
            p.pheomelanin_absorption = ph;
            p.water_fraction = water;
            p
        },
    )
}

fn grid() -> WavelengthGrid {
    WavelengthGrid::uniform(380.0, 780.0, 5.0)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn every_coefficient_is_finite_and_positive(p in any_params()) {
        let o = skin::evaluate(&p, &grid()).unwrap();
        for l in &o.layers {
            prop_assert!(l.d_mm.is_finite() && l.d_mm > 0.0, "{} d = {}", l.name, l.d_mm);
            prop_assert!(l.eta > 1.0);
            for (&a, &s) in l.mua_per_mm.iter().zip(&l.musp_per_mm) {
                prop_assert!(a.is_finite() && a > 0.0, "{} μa = {a}", l.name);
                prop_assert!(s.is_finite() && s > 0.0, "{} μs′ = {s}", l.name);
            }
        }
        let s = o.surface;
        prop_assert!(s.beckmann_m > 0.0 && s.beckmann_m <= s.alpha_sr_rad);
        prop_assert!(s.f0 > 0.0 && s.f0 < 1.0);
        prop_assert!(o.junction.amplitude_mm >= 0.0);
    }

    #[test]
    fn older_skin_is_thinner_with_less_melanin_and_hemoglobin(p in any_params(), dt in 0.5..=40.0f64) {
        let mut older = p.clone();
        older.age_years = (p.age_years + dt).min(90.0);
        let (a, b) = (skin::evaluate(&p, &grid()).unwrap(), skin::evaluate(&older, &grid()).unwrap());
        let (ia, ib) = (&a.intermediate, &b.intermediate);
        for i in 0..5 {
            prop_assert!(ib.thickness_mm[i] <= ia.thickness_mm[i]);
        }
        prop_assert!(ib.melanosome_fraction <= ia.melanosome_fraction);
        prop_assert!(ib.blood_fraction_pd <= ia.blood_fraction_pd);
        prop_assert!(ib.blood_fraction_rd <= ia.blood_fraction_rd);
        prop_assert!(b.junction.amplitude_mm <= a.junction.amplitude_mm);
        prop_assert!(b.surface.rz_um >= a.surface.rz_um);
        // Strictly, once both ages are past 30 and the living epidermis atrophies.
        if p.age_years >= 30.0 && older.age_years > p.age_years + 0.1 {
            prop_assert!(ib.thickness_mm[1] < ia.thickness_mm[1]);
            prop_assert!(ib.blood_fraction_pd < ia.blood_fraction_pd);
            if ia.melanosome_fraction > 0.0 {
                prop_assert!(ib.melanosome_fraction < ia.melanosome_fraction);
            }
        }
    }

    #[test]
    fn more_exposure_means_less_hemoglobin(p in any_params(), dxi in 0.01..=1.0f64) {
        let mut low = p.clone();
        low.xi = (p.xi - dxi).max(0.0);
        let (a, b) = (skin::evaluate(&low, &grid()).unwrap(), skin::evaluate(&p, &grid()).unwrap());
        prop_assert!(b.intermediate.blood_fraction_pd <= a.intermediate.blood_fraction_pd);
        prop_assert!(b.intermediate.blood_fraction_rd <= a.intermediate.blood_fraction_rd);
        if p.age_years > 30.5 && p.xi > low.xi {
            prop_assert!(b.intermediate.blood_fraction_pd < a.intermediate.blood_fraction_pd);
        }
    }
}
