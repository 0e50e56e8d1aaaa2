//! Spectral checks on Fig. 35's example (30-year-old woman, type II, ϑm = 3 %, ϑHb = 1 %).

use baker::skin::{self, BodyLocation, Gender, MelaninInput, SkinParams, SkinType};
use baker::spectral::WavelengthGrid;

fn fig35() -> skin::SkinOptics {
    let mut p = SkinParams::new(
        30.0,
        Gender::Female,
        BodyLocation::Forearm,
        MelaninInput::SkinType(SkinType::II),
        1.0,
    );
    p.blood_fraction_pd = 0.01;
    p.blood_fraction_rd = 0.01;
    assert_eq!(
        p.melanosome_fraction_at_30(),
        0.03,
        "type II maps to Fig. 35's 3 %"
    );
    skin::evaluate(&p, &WavelengthGrid::uniform(400.0, 700.0, 1.0)).unwrap()
}

fn argmax_in(lam: &[f64], v: &[f64], lo: f64, hi: f64) -> f64 {
    let (mut best, mut at) = (f64::MIN, 0.0);
    for (l, x) in lam.iter().zip(v) {
        if *l >= lo && *l <= hi && *x > best {
            best = *x;
            at = *l;
        }
    }
    at
}

fn is_local_max(lam: &[f64], v: &[f64], at: f64) -> bool {
    let i = lam.iter().position(|l| *l == at).unwrap();
    v[i] > v[i - 1] && v[i] >= v[i + 1]
}

#[test]
fn dermal_layers_show_soret_peak_and_q_bands() {
    let o = fig35();
    let lam = &o.lambda_nm;
    for layer in &o.layers[2..4] {
        let mua = &layer.mua_per_mm;
        // Soret band: HbO2 peaks at 414 nm, Hb at 430 nm; 75 % saturation puts it near 415.
        let soret = argmax_in(lam, mua, 400.0, 450.0);
        assert!(
            (410.0..=421.0).contains(&soret),
            "{}: Soret peak at {soret} nm",
            layer.name
        );
        // Q bands of oxy-hemoglobin at 542 and 577 nm.
        for (lo, hi, q) in [(530.0, 555.0, 542.0), (565.0, 590.0, 577.0)] {
            let peak = argmax_in(lam, mua, lo, hi);
            assert!(
                (peak - q).abs() <= 3.0,
                "{}: Q band near {q} found at {peak}",
                layer.name
            );
            assert!(
                is_local_max(lam, mua, peak),
                "{}: {peak} nm is not a local maximum",
                layer.name
            );
        }
        // Between the Q bands, absorption dips (the 560 nm valley).
        let i = |l: f64| lam.iter().position(|x| *x == l).unwrap();
        assert!(mua[i(560.0)] < mua[i(542.0)] && mua[i(560.0)] < mua[i(577.0)]);
    }
}

#[test]
fn living_epidermis_absorption_falls_monotonically() {
    let o = fig35();
    let le = &o.layers[1];
    assert_eq!(le.name, "living epidermis");
    for w in le.mua_per_mm.windows(2) {
        assert!(w[1] < w[0], "living epidermis μa not decreasing: {w:?}");
    }
}

#[test]
fn reference_wavelength_scattering_matches_section_3_4_4() {
    let o = fig35();
    let i = o.lambda_nm.iter().position(|l| *l == 500.0).unwrap();
    // At λr = 500 nm Eqs. 5–7 reduce to μs′(λr): 6.67 mm⁻¹ epidermal, 4.36 mm⁻¹ dermal.
    assert!((o.layers[0].musp_per_mm[i] - 6.67).abs() < 1e-12);
    assert!((o.layers[1].musp_per_mm[i] - 6.67).abs() < 1e-12);
    assert!((o.layers[2].musp_per_mm[i] - 4.36).abs() < 1e-9);
    assert!((o.layers[3].musp_per_mm[i] - 4.36).abs() < 1e-9);
    // Eq. 10: 105.06·500^-0.68.
    assert!((o.layers[4].musp_per_mm[i] - 105.06 * 500f64.powf(-0.68)).abs() < 1e-12);
}

#[test]
fn melanin_dominates_epidermis_and_blood_the_dermis_in_the_blue() {
    let o = fig35();
    let i = o.lambda_nm.iter().position(|l| *l == 415.0).unwrap();
    // Fig. 35 (right): the living epidermis absorbs most at short wavelengths.
    assert!(o.layers[1].mua_per_mm[i] > o.layers[2].mua_per_mm[i]);
    // More blood in the papillary dermis raises its Soret absorption proportionally.
    let mut p = SkinParams::new(
        30.0,
        Gender::Female,
        BodyLocation::Forearm,
        MelaninInput::SkinType(SkinType::II),
        1.0,
    );
    p.blood_fraction_pd = 0.02;
    p.blood_fraction_rd = 0.01;
    let o2 = skin::evaluate(&p, &WavelengthGrid::uniform(400.0, 700.0, 1.0)).unwrap();
    assert!(o2.layers[2].mua_per_mm[i] > 1.8 * o.layers[2].mua_per_mm[i]);
}

#[test]
fn adult_reticular_dermis_has_jacques_mie_exponent() {
    // Jacques (2013), dermis: b_Mie = 0.562. Our default collagen distribution at 30 years
    // gives the same spectral slope between 500 and 700 nm within 3 %.
    let o = fig35();
    let g = o.intermediate.gamma_effective_rd;
    assert!((g - 0.562).abs() < 0.03 * 0.562, "γ_eff(RD, 30 y) = {g}");
    // Thinner papillary fibrils scatter with a steeper spectrum (§3.4.4, Fig. 39).
    assert!(o.intermediate.gamma_effective_pd > g);
}
