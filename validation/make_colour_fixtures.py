#!/usr/bin/env python3
"""Write the colour-science reference fixtures for the baker's colour code (tests/colour/).

How to run (from anywhere; the repository root is found from this file's path):

    pip install colour-science==0.4.7 numpy      # validation/requirements.txt pins both
    python3 validation/make_colour_fixtures.py              # (re)writes tests/colour/*.csv
    python3 validation/make_colour_fixtures.py --check      # compares, writes nothing
    python3 validation/make_colour_fixtures.py --out DIR    # writes elsewhere

Generated with colour-science 0.4.7 and numpy 2.4.x under Python 3.11 (the script warns on
stderr when the installed colour-science is not 0.4.7). The output is deterministic: with the
same versions a rerun rewrites both files byte for byte. `--check` compares the numbers
(within 1e-14 relative), not the headers that name the versions, and exits 1 if they differ.

What is written (every number with 17 significant digits, `%.17g`, so it parses back to the
exact float64 colour-science computed; each file starts with `#` lines naming its source, the
command and every column with its unit, in the dialect of baker/src/files/csv_rows.rs, no
plain header row):

* tests/colour/srgb_transfer.csv  `linear,encoded`: encoded =
  colour.cctf_encoding(linear, function="sRGB") (IEC 61966-2-1: 12.92·L for L ≤ 0.0031308,
  else 1.055·L^(1/2.4) − 0.055), for 0, 1, a few tiny values, 101 uniform values and a dense
  cluster on both sides of the 0.0031308 knee (the knee itself and its float neighbours).
* tests/colour/spectra_srgb.csv  name, r400…r700 (31 reflectances), X, Y, Z, R_lin, G_lin,
  B_lin, R_enc, G_enc, B_enc, for the 24 patches of colour.SDS_COLOURCHECKERS["ColorChecker N
  Ohta"], three synthetic spectra and the perfect white diffuser (R ≡ 1):
  - resampling: every 10 nm point of the grid SHAPE = SpectralShape(400, 700, 10) is a native
    sample of each source (Ohta: 380–780 nm at 5 nm; synthetic: 360–830 nm at 1 nm), so
    resampling is the identity and the r columns are the source's own samples. colour's own
    resampling, colour.colorimetry.reshape_sd(sd, SHAPE) (method "Align":
    SpectralDistribution.interpolate with the SD's interpolator, SpragueInterpolator for these
    uniform data (CIE 167:2005), then extrapolate/trim), returns the same numbers up to the
    interpolator's round-off at the nodes (asserted ≤ 2e-15 of the spectrum's max; the report
    prints the measured value, 9.3e-16 relative with 0.4.7). XYZ is then computed from a
    SpectralDistribution holding exactly the 31 written values, so the fixture is
    self-consistent to the last bit: no further resampling of R happens inside sd_to_XYZ;
  - XYZ = colour.sd_to_XYZ(sd, CIE 1931 2° observer, D65, method="Integration",
    shape=SHAPE) / 100: colour reshapes the CMFs and D65 to SHAPE too (again native samples)
    and returns 100·Σ R·S·c̄·Δλ / Σ S·ȳ·Δλ with Δλ = 10 nm; /100 gives Y = 1 for the white;
  - R_lin, G_lin, B_lin = (M·XYZ) / (M·XYZ_white) per channel, with M =
    colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB (the 4-digit IEC 61966-2-1 matrix) and
    XYZ_white the same integration of R ≡ 1 (M·XYZ is cross-checked against
    colour.XYZ_to_RGB(…, chromatic_adaptation_transform=None));
  - R_enc, G_enc, B_enc = colour.cctf_encoding(clip(R_lin, 0, 1), function="sRGB").
  Synthetic spectra (defined analytically at 1 nm, 360–830 nm):
    gaussian_450nm  0.02 + 0.9·exp(−(λ−450)²/(2·10²))
    gaussian_610nm  0.02 + 0.9·exp(−(λ−610)²/(2·10²))
    step_550nm      0.05 for λ < 550, 0.5 at 550, 0.95 for λ > 550

Besides writing, the script prints a report used by tests/colour/README.md:
  1. the embedded tables baker/src/spectral/data/cie1931_2deg.csv and illuminant_d65.csv
     against colour's datasets at 400–700 nm step 10 nm (and over their whole range): max
     absolute and relative difference;
  2. a float-for-float emulation of baker/src/spectral/colour.rs (ColourMap::new/xyz/rgb,
     srgb_encode) fed with the embedded tables and the fixture's reflectances: max |difference|
     from the fixture per column group — what the Rust test should see;
  3. how far a few deliberate bugs move the outputs (the margin the tolerances leave).
"""

from __future__ import annotations

import argparse
import importlib.metadata
import math
import sys
import warnings
from pathlib import Path

import numpy as np

with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    import colour
    from colour.colorimetry import reshape_msds, reshape_sd

REPO = Path(__file__).resolve().parent.parent
OUT_DEFAULT = REPO / "tests" / "colour"
DATA = REPO / "baker" / "src" / "spectral" / "data"
PINNED_COLOUR = "0.4.7"

SHAPE = colour.SpectralShape(400, 700, 10)
WL = SHAPE.wavelengths  # 400, 410, …, 700
CMFS_NAME = "CIE 1931 2 Degree Standard Observer"
CMFS = colour.MSDS_CMFS[CMFS_NAME]
D65 = colour.SDS_ILLUMINANTS["D65"]
SRGB = colour.RGB_COLOURSPACES["sRGB"]
M = np.asarray(SRGB.matrix_XYZ_to_RGB, dtype=float)
CHECKER = "ColorChecker N Ohta"
KNEE = 0.0031308
RESAMPLE_ERR = [0.0]  # max relative |reshape_sd(sd, SHAPE) − native sample|

# Proposed test tolerances (absolute), see tests/colour/README.md.
TOL = {"encoded": 1e-12, "XYZ": 1e-12, "lin": 1e-12, "enc": 1e-12}

COMMAND = "python3 validation/make_colour_fixtures.py"


def versions() -> str:
    v = {}
    for pkg in ("colour-science", "numpy"):
        try:
            v[pkg] = importlib.metadata.version(pkg)
        except importlib.metadata.PackageNotFoundError:
            v[pkg] = "?"
    if v["colour-science"] != PINNED_COLOUR:
        print(f"warning: colour-science {v['colour-science']} installed, fixtures were made "
              f"with {PINNED_COLOUR}", file=sys.stderr)
    py = ".".join(map(str, sys.version_info[:3]))
    return f"colour-science {v['colour-science']}, numpy {v['numpy']}, Python {py}"


def g17(x: float) -> str:
    s = "%.17g" % float(x)
    assert float(s) == float(x) or (math.isnan(x) and s == "nan")
    return s


def encode(x):
    """colour's sRGB inverse EOTF (no clamping: callers clamp)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return np.asarray(colour.cctf_encoding(np.asarray(x, dtype=float), function="sRGB"), float)


# ---------------------------------------------------------------------------- transfer

def transfer_inputs() -> np.ndarray:
    vals = {0.0, 1.0}
    # tiny values (the smallest subnormal, the smallest normal, …)
    vals |= {5e-324, 2.2250738585072014e-308, 1e-300, 1e-15, 1e-12, 1e-9, 1e-7, 1e-6, 1e-5,
             1e-4, 1e-3}
    # 0, 0.01, …, 1
    vals |= {i / 100 for i in range(101)}
    # near 1 and the usual mid grey
    vals |= {0.18, 0.5, 0.999, 1 - 1e-6, 1 - 1e-12, float(np.nextafter(1.0, 0.0))}
    # the knee, its float neighbours, relative offsets 1e-1 … 1e-9 on both sides
    vals |= {KNEE, float(np.nextafter(KNEE, 0.0)), float(np.nextafter(KNEE, 1.0))}
    for k in range(1, 10):
        vals |= {KNEE * (1 - 10.0 ** -k), KNEE * (1 + 10.0 ** -k)}
    # log-spaced from knee/30 to knee·30 (dense on both sides of the knee)
    vals |= set(np.geomspace(KNEE / 30, KNEE * 30, 41).tolist())
    # linear-spaced ±20 % around the knee
    vals |= set(np.linspace(0.8 * KNEE, 1.2 * KNEE, 21).tolist())
    x = np.array(sorted(vals))
    assert x[0] == 0.0 and x[-1] == 1.0
    return x


def transfer_text(ver: str) -> tuple[str, int]:
    x = transfer_inputs()
    y = encode(x)
    lines = [
        "# sRGB transfer function (IEC 61966-2-1:1999 inverse EOTF), linear -> encoded, both dimensionless in [0, 1]",
        f"# Source: colour.cctf_encoding(linear, function='sRGB') from {ver}: 12.92*L for L <= 0.0031308, else 1.055*L^(1/2.4) - 0.055",
        f"# Generated by: {COMMAND}  (values printed with 17 significant digits, %.17g: they parse back to the exact float64)",
        f"# {len(x)} rows: 0, 1, tiny values, 0.00..1.00 step 0.01, and a dense cluster on both sides of the knee 0.0031308 (incl. the knee and its float neighbours)",
        "# Columns: linear,encoded",
    ]
    lines += [f"{g17(a)},{g17(b)}" for a, b in zip(x, y)]
    return "\n".join(lines) + "\n", len(x)


# ----------------------------------------------------------------------------- spectra

def synthetic() -> list[colour.SpectralDistribution]:
    lam = np.arange(360.0, 831.0, 1.0)

    def gauss(mu):
        return 0.02 + 0.9 * np.exp(-((lam - mu) ** 2) / (2 * 10.0**2))

    step = np.where(lam < 550, 0.05, np.where(lam > 550, 0.95, 0.5))
    return [
        colour.SpectralDistribution(dict(zip(lam, gauss(450.0))), name="gaussian_450nm"),
        colour.SpectralDistribution(dict(zip(lam, gauss(610.0))), name="gaussian_610nm"),
        colour.SpectralDistribution(dict(zip(lam, step)), name="step_550nm"),
    ]


def sd_xyz(sd) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return np.asarray(colour.sd_to_XYZ(sd, CMFS, D65, method="Integration", shape=SHAPE),
                          float) / 100


def spectra_rows():
    """[(name, R[31], XYZ[3], lin[3], enc[3])] and XYZ_white."""
    sds = list(colour.SDS_COLOURCHECKERS[CHECKER].values()) + synthetic()
    white_sd = colour.SpectralDistribution(dict(zip(WL, np.ones(len(WL)))),
                                           name="perfect_white_diffuser")
    xyz_w = sd_xyz(white_sd)
    white_rgb = M @ xyz_w
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        alt = np.asarray(colour.XYZ_to_RGB(xyz_w, SRGB, chromatic_adaptation_transform=None,
                                           apply_cctf_encoding=False), float)
    assert np.max(np.abs(alt - white_rgb)) < 1e-15, (alt, white_rgb)
    rows = []
    for sd in sds + [white_sd]:
        name = sd.name
        assert "," not in name and '"' not in name, name
        # The source's own samples at 400, 410, …, 700 nm (all are native samples).
        native = np.asarray(sd.values, float)[np.isin(sd.domain, WL)]
        assert len(native) == len(WL), name
        # colour's resampling to SHAPE (Sprague/linear interpolation at the nodes) gives the
        # same numbers up to interpolation round-off (≤ 1e-15 relative, reported below).
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            resampled = np.asarray(reshape_sd(sd, SHAPE).values, float)
        assert np.max(np.abs(resampled - native)) <= 2e-15 * np.max(np.abs(native)), name
        RESAMPLE_ERR[0] = max(RESAMPLE_ERR[0], float(np.max(np.abs(resampled - native)
                                                             / np.abs(native))))
        r = native
        sd31 = colour.SpectralDistribution(dict(zip(WL, r)), name=name)
        xyz = sd_xyz(sd31)
        # colour with the 31-sample SD == colour with the same values as an array.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            xyz_arr = np.asarray(colour.sd_to_XYZ(r, CMFS, D65, method="Integration",
                                                  shape=SHAPE), float) / 100
        assert np.max(np.abs(xyz - xyz_arr)) < 1e-15, name
        rgb = M @ xyz
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            alt = np.asarray(colour.XYZ_to_RGB(xyz, SRGB, chromatic_adaptation_transform=None,
                                               apply_cctf_encoding=False), float)
        assert np.max(np.abs(alt - rgb)) < 1e-15, name
        lin = rgb / white_rgb
        enc = encode(np.clip(lin, 0.0, 1.0))
        rows.append((name, r, xyz, lin, enc))
    return rows, xyz_w


def spectra_text(ver: str, rows, xyz_w) -> str:
    cols = (["name"] + [f"r{int(l)}" for l in WL]
            + ["X", "Y", "Z", "R_lin", "G_lin", "B_lin", "R_enc", "G_enc", "B_enc"])
    lines = [
        "# Reflectance spectra -> CIE XYZ (1931 2 deg observer, illuminant D65) -> linear sRGB (per-channel white-normalised) -> encoded sRGB",
        f"# Source: {ver}; colour.SDS_COLOURCHECKERS['{CHECKER}'] (24 patches, 380-780 nm at 5 nm), three synthetic spectra (1 nm, 360-830 nm: 0.02+0.9*exp(-(l-450)^2/(2*10^2)), same at 610 nm, step 0.05 | 0.5 at 550 | 0.95) and the perfect white diffuser (R = 1)",
        "# Resampling: every 400..700/10 nm point is a native sample of each source, so r400..r700 are the source's own samples; colour.colorimetry.reshape_sd(sd, SpectralShape(400, 700, 10)) (method 'Align', Sprague interpolation per CIE 167:2005) returns the same values to <= 1e-15 relative (interpolator round-off at the nodes)",
        f"# XYZ = colour.sd_to_XYZ(SpectralDistribution(r400..r700), colour.MSDS_CMFS['{CMFS_NAME}'], colour.SDS_ILLUMINANTS['D65'], method='Integration', shape=SpectralShape(400, 700, 10)) / 100 = sum(R*S*cmf) / sum(S*ybar) on the 31 samples (colour reshapes the CMFs and D65 to that shape: native samples again); the white has Y = 1",
        f"# XYZ_white (R = 1) = {g17(xyz_w[0])}, {g17(xyz_w[1])}, {g17(xyz_w[2])}",
        "# RGB_lin = (M . XYZ) / (M . XYZ_white) per channel, M = colour.RGB_COLOURSPACES['sRGB'].matrix_XYZ_to_RGB = [[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]]",
        "# RGB_enc = colour.cctf_encoding(clip(RGB_lin, 0, 1), function='sRGB')",
        f"# Generated by: {COMMAND}  (numbers printed with 17 significant digits, %.17g: they parse back to the exact float64)",
        "# Units: name text; r400..r700 reflectance at 400, 410, ..., 700 nm (dimensionless, 0..1); X, Y, Z dimensionless (Y = 1 for R = 1); R_lin, G_lin, B_lin linear sRGB (1 = white; may be < 0 or > 1); R_enc, G_enc, B_enc encoded sRGB in [0, 1]",
        "# Columns: " + ",".join(cols),
    ]
    for name, r, xyz, lin, enc in rows:
        lines.append(",".join([name] + [g17(v) for v in (*r, *xyz, *lin, *enc)]))
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------- report (README numbers)

def read_table(path: Path) -> np.ndarray:
    rows = [list(map(float, ln.split(","))) for ln in path.read_text().splitlines()
            if ln.strip() and not ln.lstrip().startswith("#")]
    return np.array(rows)


def table_at(tab: np.ndarray, col: int, l: float) -> float:
    """baker/src/spectral/table.rs SpectralTable::at (linear, ends held), float for float."""
    x, v = tab[:, 0], tab[:, col]
    if l <= x[0]:
        return float(v[0])
    if l >= x[-1]:
        return float(v[-1])
    j = int(np.searchsorted(x, l, side="right"))
    x0, x1 = float(x[j - 1]), float(x[j])
    t = (l - x0) / (x1 - x0)
    return float(v[j - 1]) * (1.0 - t) + float(v[j]) * t


class RustColourMap:
    """baker/src/spectral/colour.rs ColourMap, operation for operation (Python floats are
    IEEE doubles; Rust does not contract to FMA), so its rounding is the Rust code's."""

    def __init__(self, lam, cmf_tab, d65_tab, m=None, ends_full=True):
        m = M.tolist() if m is None else m
        n = len(lam)

        def width(i):
            lo = lam[0] if i == 0 else 0.5 * (lam[i - 1] + lam[i])
            hi = lam[n - 1] if i == n - 1 else 0.5 * (lam[i] + lam[i + 1])
            w = hi - lo
            return 2.0 * w if (ends_full and (i == 0 or i == n - 1)) else w

        raw, norm = [], 0.0
        for i, l in enumerate(lam):
            s = table_at(d65_tab, 1, l) * width(i)
            w = [s * table_at(cmf_tab, c + 1, l) for c in range(3)]
            norm += w[1]
            raw.append(w)
        self.w = [[w[0] / norm, w[1] / norm, w[2] / norm] for w in raw]
        white_xyz = [sum_seq(w[c] for w in self.w) for c in range(3)]
        self.m = m
        self.white_rgb = self.mat_vec(white_xyz)

    def mat_vec(self, v):
        return [sum_seq(self.m[r][c] * v[c] for c in range(3)) for r in range(3)]

    def xyz(self, r):
        return [sum_seq(ri * wi[c] for ri, wi in zip(r, self.w)) for c in range(3)]

    def rgb(self, r, normalise=True):
        rgb = self.mat_vec(self.xyz(r))
        return [rgb[c] / self.white_rgb[c] for c in range(3)] if normalise else rgb


def sum_seq(it) -> float:
    acc = 0.0
    for v in it:
        acc += v
    return acc


def srgb_encode(x: float, gamma=2.4, knee=KNEE, le=True) -> float:
    """baker/src/spectral/colour.rs srgb_encode."""
    x = min(max(x, 0.0), 1.0)
    below = x <= knee if le else x < knee
    return 12.92 * x if below else 1.055 * x ** (1.0 / gamma) - 0.055


def report(rows, xyz_w) -> None:
    cmf_tab = read_table(DATA / "cie1931_2deg.csv")
    d65_tab = read_table(DATA / "illuminant_d65.csv")

    print("1. embedded tables vs colour-science datasets")
    lam = cmf_tab[:, 0]
    same_dom = np.array_equal(np.asarray(CMFS.domain, float), lam)
    d = np.abs(cmf_tab[:, 1:4] - np.asarray(CMFS.values, float)) if same_dom else [np.inf]
    print(f"   CMF 360-830 nm at 1 nm vs colour's stored table: same wavelengths {same_dom}, "
          f"max abs diff {np.max(d):.3g}")
    sel = np.isin(lam, WL)
    ours = cmf_tab[sel, 1:4]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        used = np.asarray(reshape_msds(CMFS, SHAPE).values, float)
    d = np.abs(ours - used)
    nz = ours != 0
    print(f"   CMF 400-700 nm step 10, ours vs what sd_to_XYZ integrates (reshape_msds, Sprague "
          f"evaluated at the nodes): max abs {d.max():.3g}, max rel {np.max(d[nz] / ours[nz]):.3g}"
          f", where ours is 0: {np.max(np.abs(used[~nz])):.3g}")
    ours = np.array([table_at(d65_tab, 1, l) for l in WL])
    nat = np.asarray(D65.values, float)[np.isin(D65.domain, WL)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        used = np.asarray(reshape_sd(D65, SHAPE).values, float)
    print(f"   D65 400-700 nm step 10: ours vs colour's stored max rel "
          f"{np.max(np.abs(ours - nat) / nat):.3g}, vs what sd_to_XYZ integrates "
          f"{np.max(np.abs(ours - used) / used):.3g}")
    d_lam = d65_tab[:, 0][(d65_tab[:, 0] <= 780) & (d65_tab[:, 0] % 5 == 0)]
    ours = d65_tab[np.isin(d65_tab[:, 0], d_lam), 1]
    ref = np.asarray(D65.values, float)[np.isin(D65.domain, d_lam)]
    print(f"   D65 {d_lam[0]:.0f}-780 nm at colour's 5 nm nodes: max rel "
          f"{np.max(np.abs(ours - ref) / ref):.3g}")
    print(f"   reflectances: colour's reshape_sd to 400-700/10 vs the native samples written: "
          f"max rel {RESAMPLE_ERR[0]:.3g}")

    print("2. emulated baker colour.rs vs the fixture (max |difference|)")
    cm = RustColourMap(list(map(float, WL)), cmf_tab, d65_tab)
    dx = dl = de = 0.0
    for name, r, xyz, lin, enc in rows:
        r = list(map(float, r))
        dx = max(dx, *np.abs(np.array(cm.xyz(r)) - xyz))
        ours = cm.rgb(r)
        dl = max(dl, *np.abs(np.array(ours) - lin))
        de = max(de, *np.abs(np.array([srgb_encode(v) for v in ours]) - enc))
    print(f"   XYZ {dx:.3g}   RGB_lin {dl:.3g}   RGB_enc {de:.3g}   "
          f"(white XYZ here {cm.xyz([1.0] * len(WL))} vs fixture {xyz_w.tolist()})")
    x = transfer_inputs()
    dt = np.max(np.abs(np.array([srgb_encode(float(v)) for v in x]) - encode(x)))
    print(f"   srgb_encode over srgb_transfer.csv: {dt:.3g}")

    print("3. deliberate bugs in the emulation: max |change| vs the fixture "
          f"(tolerance {TOL['lin']:g})")

    def worst(cm2, enc_fn=srgb_encode, normalise=True):
        dl = de = 0.0
        for name, r, xyz, lin, enc in rows:
            ours = cm2.rgb(list(map(float, r)), normalise)
            dl = max(dl, *np.abs(np.array(ours) - lin))
            de = max(de, *np.abs(np.array([enc_fn(v) for v in ours]) - enc))
        return dl, de

    mt = M.tolist()
    cases = {
        "gamma 1/2.2": (cm, lambda v: srgb_encode(v, gamma=2.2), True),
        "knee '<' instead of '<='": (cm, lambda v: srgb_encode(v, le=False), True),
        "knee 0.04045 (EOTF's) ": (cm, lambda v: srgb_encode(v, knee=0.04045), True),
        "M rows 0<->1 swapped": (RustColourMap(list(map(float, WL)), cmf_tab, d65_tab,
                                               [mt[1], mt[0], mt[2]]), srgb_encode, True),
        "M rows 1<->2 swapped": (RustColourMap(list(map(float, WL)), cmf_tab, d65_tab,
                                               [mt[0], mt[2], mt[1]]), srgb_encode, True),
        "M transposed": (RustColourMap(list(map(float, WL)), cmf_tab, d65_tab,
                                       np.array(mt).T.tolist()), srgb_encode, True),
        "M = Lindbloom 3.2404542…": (RustColourMap(list(map(float, WL)), cmf_tab, d65_tab,
                                     [[3.2404542, -1.5371385, -0.4985314],
                                      [-0.9692660, 1.8760108, 0.0415560],
                                      [0.0556434, -0.2040259, 1.0572252]]), srgb_encode, True),
        "no white normalisation": (cm, srgb_encode, False),
        "half-width end bins": (RustColourMap(list(map(float, WL)), cmf_tab, d65_tab,
                                              ends_full=False), srgb_encode, True),
    }
    for label, (cm2, enc_fn, normalise) in cases.items():
        dl, de = worst(cm2, enc_fn, normalise)
        print(f"   {label:28s} RGB_lin {dl:.3g}   RGB_enc {de:.3g}")
    dt = np.max(np.abs(np.array([srgb_encode(float(v), gamma=2.2) for v in x]) - encode(x)))
    dk = np.max(np.abs(np.array([srgb_encode(float(v), le=False) for v in x]) - encode(x)))
    dk2 = np.max(np.abs(np.array([srgb_encode(float(v), knee=0.04045) for v in x]) - encode(x)))
    print(f"   transfer table: gamma 1/2.2 {dt:.3g}, knee '<' {dk:.3g}, knee 0.04045 {dk2:.3g}")


def same_values(path: Path, text: str, rel: float = 1e-14) -> tuple[bool, str]:
    """Whether the file at `path` holds the same rows as `text` (names equal, numbers within
    `rel` relative): header lines, which name the versions, do not count, so a CI machine
    with another patch release of Python or numpy checks the numbers, not the header."""
    if not path.exists():
        return False, ", missing"
    def rows(t):
        return [line.split(",") for line in t.splitlines() if line and not line.startswith("#")]
    a, b = rows(path.read_text()), rows(text)
    if len(a) != len(b):
        return False, f", {len(a)} rows in the file"
    worst = 0.0
    for ra, rb in zip(a, b):
        if len(ra) != len(rb):
            return False, ", a row has another length"
        for x, y in zip(ra, rb):
            try:
                fx, fy = float(x), float(y)
            except ValueError:
                if x != y:
                    return False, f", {x!r} vs {y!r}"
                continue
            d = abs(fx - fy) / max(abs(fx), abs(fy), 1e-300)
            worst = max(worst, d)
    return worst <= rel, f", largest relative difference {worst:.1e}"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=OUT_DEFAULT, help="output folder (tests/colour)")
    ap.add_argument("--check", action="store_true",
                    help="compare with the files in --out instead of writing them")
    ap.add_argument("--no-report", action="store_true", help="skip the printed report")
    args = ap.parse_args()

    ver = versions()
    transfer, n_t = transfer_text(ver)
    rows, xyz_w = spectra_rows()
    spectra = spectra_text(ver, rows, xyz_w)
    files = {"srgb_transfer.csv": (transfer, n_t), "spectra_srgb.csv": (spectra, len(rows))}
    bad = 0
    for fname, (text, n) in files.items():
        path = args.out / fname
        if args.check:
            same, what = same_values(path, text)
            print(f"{path}: {'same values' if same else 'DIFFERS'} ({n} rows{what})")
            bad += not same
        else:
            args.out.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
            print(f"wrote {path} ({n} rows)")
    if not args.no_report:
        report(rows, xyz_w)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
