#!/usr/bin/env python3
"""Independent check of the skin diffusion-profile bake (`baker bake`).

How to run (from anywhere; the repository root is found from this file's path):

    pip install -r validation/requirements.txt
    python3 validation/check_profiles.py --baker target/release/baker \\
        --spec tests/specs/profiles_small.yaml --photons 20000      # bakes into a temp dir
    python3 validation/check_profiles.py --out DIR                  # check an existing bake
    ... --fit-thresholds [--max-error 0.05,0.03,0.03]  --rerun  --keep DIR

Without --out the script runs `BAKER bake SPEC --out TMP --quiet [--photons N]` (building
target/release/baker with cargo when --baker is not given) and checks TMP/<spec stem>/.
--out DIR accepts either that spec directory or its parent (with --spec, or with a single
sub-directory holding profiles.h5).

Colour reference: CIE 1931 2° standard observer and CIE standard illuminant D65 (CIE 015:2018)
and the sRGB primaries/matrix of IEC 61966-2-1:1999, all taken from colour-science 0.4.7
(`colour.MSDS_CMFS`, `colour.SDS_ILLUMINANTS`, `colour.RGB_COLOURSPACES["sRGB"]`), never from
the baker. XYZ = sd_to_XYZ(R, cmfs, D65, method="Integration", shape=file grid)/100, i.e.
Σ R·S·cmf·Δλ / Σ S·ȳ·Δλ with constant Δλ (uniform grids only); linear sRGB =
XYZ_to_RGB(XYZ, sRGB, chromatic_adaptation_transform=None) / (same for R ≡ 1).
Gaussian sum: G(v, r) = exp(−r²/2v)/(2πv), whose exact average over the annulus [a, b] is
(exp(−a²/2v) − exp(−b²/2v))/(π(b²−a²)).

Checks (one PASS/FAIL line each, with the worst discrepancy):
  layout   root attrs (format, format_version, spec_file, photons, seed), datasets and shapes
  1 colour xyz, albedo_rgb vs colour-science from rd_total_spectral (1e-4 abs); /colour tables
           vs colour-science (xyz_weights 1e-9 of max, rgb_from_xyz, white_rgb) and white → (1,1,1)
  2 rgb    rd_rgb_per_mm2, albedo_rgb, xyz = the file's linear map of the spectral tables
           (1e-9 of the channel max); *_se = sqrt(Σ_λ c_λ² se_λ²)
  3 energy Σ_k rd_spectral·area_k ≤ rd_total + 3 se; r_mm = bin centres; r99 recomputed (1e-6
           rel., linear in r inside the bin) and r99 < r_edges[-1]
  4 fit    error_rgb recomputed from the Gaussians over bins with r_edges[k] < r99 (1e-6 abs);
           weights ≥ 0, variances > 0; with --fit-thresholds, error ≤ --max-error + the error the
           table's own noise gives a perfect fit (noise_l1)
  5 bkt    every dataset of /colour and the entry groups is in profiles.bkt, exactly equal
  6 exr    profiles_rgb.exr: one row per entry, R,G,B = float32(rd_rgb_per_mm2), r_mm = centres
  7 manifest entries (names, params) and every file's sha256 and size; previews present
  8 rerun  (--rerun) a second bake gives a byte-identical profiles.bkt and identical HDF5 data
Finally prints `check_profiles: N passed, M failed`; exits with 1 if any check fails.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

try:
    import h5py
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour
except ImportError as e:  # pragma: no cover
    sys.exit(f"{e.name} is not installed: pip install -r validation/requirements.txt")

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))  # validation/bkt.py

TOL_COLOUR, TOL_WEIGHTS, TOL_MAP, TOL_R99, TOL_FIT, K_SE = 1e-4, 1e-9, 1e-9, 1e-6, 1e-6, 3.0
SRGB = colour.RGB_COLOURSPACES["sRGB"]
SHOW = 8  # failure lines shown per check


class Missing(Exception):
    pass


class Bake:
    """All datasets and attributes of profiles.h5, loaded into memory."""

    def __init__(self, path: Path):
        self.data: dict[str, np.ndarray] = {}
        self.attrs: dict[str, dict] = {}
        with h5py.File(path, "r") as f:
            self.root = dict(f.attrs)
            self.groups = [k for k in f.keys() if k != "colour" and isinstance(f[k], h5py.Group)]
            f.visititems(self._visit)

    def _visit(self, name, obj):
        if isinstance(obj, h5py.Dataset):
            self.data[name] = obj[()]
        else:
            self.attrs[name] = dict(obj.attrs)

    def get(self, entry: str, name: str) -> np.ndarray:
        key = f"{entry}/{name}"
        if key not in self.data:
            raise Missing(f"{entry}: dataset /{key} missing")
        return np.asarray(self.data[key], dtype=float)

    def dataset_paths(self) -> list[str]:
        return sorted(self.data)


def text(v) -> str:
    if isinstance(v, (bytes, np.bytes_)):
        return v.decode()
    if isinstance(v, np.ndarray) and v.shape == ():
        return text(v[()])
    return str(v)


def colour_map(lam: np.ndarray):
    """(W [nλ,3], M [3,3], white [3]) from colour-science for the grid lam (must be uniform)."""
    step = lam[1] - lam[0]
    if len(lam) < 2 or np.max(np.abs(np.diff(lam) - step)) > 1e-9 * step:
        raise ValueError(f"wavelength grid is not uniform: {lam}")
    shape = colour.SpectralShape(float(lam[0]), float(lam[-1]), float(step))
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        W = colour.sd_to_XYZ(np.eye(len(lam)), cmfs, d65, method="Integration", shape=shape) / 100
        white = colour.XYZ_to_RGB(W.sum(axis=0), SRGB, chromatic_adaptation_transform=None,
                                  apply_cctf_encoding=False)
    return W, np.asarray(SRGB.matrix_XYZ_to_RGB, float), white


def colour_rgb(R: np.ndarray, lam: np.ndarray, white: np.ndarray):
    """XYZ and linear sRGB of reflectance spectra R[..., nλ], computed by colour-science itself."""
    shape = colour.SpectralShape(float(lam[0]), float(lam[-1]), float(lam[1] - lam[0]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        xyz = colour.sd_to_XYZ(R, colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"],
                               colour.SDS_ILLUMINANTS["D65"], method="Integration", shape=shape) / 100
        rgb = colour.XYZ_to_RGB(xyz, SRGB, chromatic_adaptation_transform=None, apply_cctf_encoding=False)
    return xyz, rgb / white


def areas(edges: np.ndarray) -> np.ndarray:
    return math.pi * (edges[1:] ** 2 - edges[:-1] ** 2)


def r99_of(rd_rgb: np.ndarray, edges: np.ndarray, albedo: np.ndarray) -> np.ndarray:
    out = np.full(3, np.inf)
    a = areas(edges)
    for c in range(3):
        e = rd_rgb[:, c] * a
        cum = np.cumsum(e)
        hit = np.nonzero(cum >= 0.99 * albedo[c])[0]
        if len(hit):
            k = hit[0]
            before = cum[k - 1] if k > 0 else 0.0
            frac = (0.99 * albedo[c] - before) / e[k] if e[k] > 0 else 1.0
            out[c] = edges[k] + frac * (edges[k + 1] - edges[k])
    return out


def fit_error(var, w, rd_rgb, edges, r99) -> np.ndarray:
    a, b = edges[:-1], edges[1:]
    area = areas(edges)
    err = np.zeros(3)
    for c in range(3):
        g = np.exp(-a[:, None] ** 2 / (2 * var)) * -np.expm1(-(b ** 2 - a ** 2)[:, None] / (2 * var))
        fit = (g / area[:, None]) @ w[:, c]
        m = a < r99[c]
        den = np.sum(rd_rgb[m, c] * area[m])
        err[c] = np.sum(np.abs(fit[m] - rd_rgb[m, c]) * area[m]) / den if den > 0 else np.inf
    return err


def rel(a, b, scale) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / scale) if np.size(a) else 0.0


# ---------------------------------------------------------------- checks (each returns (summary, failures))

def check_layout(bk: Bake, entries: list[str], photons) -> tuple[str, list[str]]:
    fails = []
    r = bk.root
    if text(r.get("format", "")) != "baker-skin-profiles":
        fails.append(f"root attr format = {r.get('format')!r}, expected 'baker-skin-profiles'")
    if int(r.get("format_version", -1)) != 1:
        fails.append(f"root attr format_version = {r.get('format_version')!r}, expected 1")
    fails += [f"root attr {k} missing" for k in ("spec_file", "photons", "seed") if k not in r]
    if photons is not None and "photons" in r and int(r["photons"]) != int(photons):
        fails.append(f"root attr photons = {r['photons']}, --photons was {photons}")
    if not entries:
        fails.append("no entry groups in profiles.h5")
    for path in ("colour/lambda_nm", "colour/xyz_weights", "colour/rgb_from_xyz", "colour/white_rgb"):
        if path not in bk.data:
            fails.append(f"/{path} missing")
    for e in entries:
        try:
            nl, nr = len(bk.get(e, "lambda_nm")), len(bk.get(e, "r_mm"))
            ng = len(bk.get(e, "gaussians/variance_mm2"))
            shapes = {"r_edges_mm": (nr + 1,), "rd_spectral_per_mm2": (nl, nr), "rd_spectral_per_mm2_se": (nl, nr),
                      "rd_total_spectral": (nl,), "rd_total_spectral_se": (nl,), "rsp_spectral": (nl,),
                      "xyz": (3,), "albedo_rgb": (3,), "albedo_rgb_se": (3,), "rd_rgb_per_mm2": (nr, 3),
                      "rd_rgb_per_mm2_se": (nr, 3), "r99_mm": (3,), "gaussians/weight_rgb": (ng, 3),
                      "gaussians/error_rgb": (3,)}
            for name, shp in shapes.items():
                if bk.get(e, name).shape != shp:
                    fails.append(f"{e}: /{e}/{name} has shape {bk.get(e, name).shape}, expected {shp}")
            if "params_json" not in bk.attrs.get(e, {}):
                fails.append(f"{e}: attribute params_json missing")
            else:
                json.loads(text(bk.attrs[e]["params_json"]))
            if not np.array_equal(bk.get(e, "lambda_nm"), bk.get("colour", "lambda_nm")):
                fails.append(f"{e}: lambda_nm differs from /colour/lambda_nm")
        except (Missing, ValueError) as ex:
            fails.append(str(ex))
    return f"{len(entries)} entries, {len(bk.data)} datasets", fails


def check_colour(bk: Bake, entries: list[str]) -> tuple[str, list[str]]:
    fails = []
    lam = bk.get("colour", "lambda_nm")
    W, M, white = colour_map(lam)
    dev = {}
    tables = (("xyz_weights", W, TOL_WEIGHTS), ("rgb_from_xyz", M, 1e-12), ("white_rgb", white, TOL_WEIGHTS))
    for name, ref, tol in tables:
        if f"colour/{name}" not in bk.data:
            fails.append(f"/colour/{name} missing")
            continue
        d = dev[name] = rel(bk.get("colour", name), ref, np.max(np.abs(ref)))
        if not d <= tol:
            fails.append(f"/colour/{name}: max deviation from colour-science {d:.3g} of max > {tol:g}")
    try:
        Mf, Wf, wf = (bk.get("colour", n) for n in ("rgb_from_xyz", "xyz_weights", "white_rgb"))
        d = rel((Mf @ Wf.sum(axis=0)) / wf, np.ones(3), 1.0)
        if not d <= 1e-10:
            fails.append(f"/colour: the file's map takes R ≡ 1 to {(Mf @ Wf.sum(axis=0)) / wf}, not (1,1,1)")
    except Missing:
        pass  # reported above
    worst = 0.0
    for e in entries:
        try:
            xyz, rgb = colour_rgb(bk.get(e, "rd_total_spectral"), bk.get(e, "lambda_nm"), white)
            for name, ref in (("xyz", xyz), ("albedo_rgb", rgb)):
                d = rel(bk.get(e, name), ref, 1.0)
                worst = max(worst, d)
                if not d <= TOL_COLOUR:
                    fails.append(f"{e}: /{e}/{name} = {bk.get(e, name)} but colour-science gives {ref} "
                                 f"(|Δ| {d:.3g} > {TOL_COLOUR:g})")
        except (Missing, ValueError) as ex:
            fails.append(str(ex))
    tab = ", ".join(f"{k} {v:.1e}" for k, v in dev.items())
    return f"worst |Δ| xyz/albedo_rgb {worst:.2e}; /colour tables vs colour-science (of max): {tab}", fails


def file_map(bk: Bake) -> np.ndarray:
    """C [3, nλ]: linear sRGB (white-normalised) of a spectrum, from the file's own /colour tables."""
    return (bk.get("colour", "rgb_from_xyz") @ bk.get("colour", "xyz_weights").T) / bk.get("colour", "white_rgb")[:, None]


def check_rgb(bk: Bake, entries: list[str]) -> tuple[str, list[str]]:
    fails, worst = [], 0.0
    C = file_map(bk)
    Wf = bk.get("colour", "xyz_weights")
    for e in entries:
        try:
            spec, se = bk.get(e, "rd_spectral_per_mm2"), bk.get(e, "rd_spectral_per_mm2_se")
            tot, tot_se = bk.get(e, "rd_total_spectral"), bk.get(e, "rd_total_spectral_se")
            pairs = (("rd_rgb_per_mm2", (C @ spec).T), ("rd_rgb_per_mm2_se", np.sqrt((C ** 2) @ (se ** 2)).T),
                     ("albedo_rgb", C @ tot), ("albedo_rgb_se", np.sqrt((C ** 2) @ tot_se ** 2)),
                     ("xyz", tot @ Wf))
            for name, ref in pairs:
                got, ref2 = np.atleast_2d(bk.get(e, name)), np.atleast_2d(ref)
                for c in range(3):
                    scale = np.max(np.abs(ref2[:, c])) or 1e-300
                    d = rel(got[:, c], ref2[:, c], scale)
                    worst = max(worst, d)
                    if not d <= TOL_MAP:
                        k = int(np.argmax(np.abs(got[:, c] - ref2[:, c])))
                        idx = f"{k},{c}" if got.shape[0] > 1 else f"{c}"
                        fails.append(f"{e}: /{e}/{name}[{idx}] = {got[k, c]:.10g}, map of spectral table "
                                     f"gives {ref2[k, c]:.10g} (rel. to channel max {d:.3g} > {TOL_MAP:g})")
        except (Missing, ValueError) as ex:
            fails.append(str(ex))
    return f"worst deviation {worst:.2e} of channel max", fails


def check_energy(bk: Bake, entries: list[str]) -> tuple[str, list[str]]:
    fails, worst_z, worst_r99, margin = [], -np.inf, 0.0, np.inf
    for e in entries:
        try:
            edges, r = bk.get(e, "r_edges_mm"), bk.get(e, "r_mm")
            if edges[0] != 0 or np.any(np.diff(edges) <= 0):
                fails.append(f"{e}: /{e}/r_edges_mm must start at 0 and increase")
                continue
            if rel(r, (edges[1:] + edges[:-1]) / 2, edges[-1]) > 1e-12:
                fails.append(f"{e}: /{e}/r_mm are not the bin centres of r_edges_mm")
            binned = bk.get(e, "rd_spectral_per_mm2") @ areas(edges)
            tot, se = bk.get(e, "rd_total_spectral"), bk.get(e, "rd_total_spectral_se")
            excess = binned - tot - K_SE * se - 1e-12 * np.abs(tot)
            z = (binned - tot) / np.where(se > 0, se, 1e-300)
            worst_z = max(worst_z, float(np.max(z)))
            for i in np.nonzero(excess > 0)[0][:3]:
                fails.append(f"{e}: λ={bk.get(e, 'lambda_nm')[i]:g} nm: Σ bins {binned[i]:.6g} > rd_total "
                             f"{tot[i]:.6g} + {K_SE:g}·se ({se[i]:.2g})")
            r99 = r99_of(bk.get(e, "rd_rgb_per_mm2"), edges, bk.get(e, "albedo_rgb"))
            got = bk.get(e, "r99_mm")
            d = float(np.max(np.abs(got - r99) / np.where(np.isfinite(r99), np.abs(r99), 1.0)))
            worst_r99 = max(worst_r99, d if np.all(np.isfinite(r99)) else np.inf)
            if not np.all(np.isfinite(r99)):
                fails.append(f"{e}: cumulative energy never reaches 99 % of albedo_rgb in some channel "
                             f"(recomputed r99 {r99}); the radial grid ends at {edges[-1]:g} mm")
            elif not d <= TOL_R99:
                fails.append(f"{e}: /{e}/r99_mm = {got} but recomputed {r99} (rel. {d:.3g} > {TOL_R99:g})")
            margin = min(margin, float(np.min(edges[-1] - got)))
            if np.any(got >= edges[-1]):
                fails.append(f"{e}: r99_mm {got} not below the last edge {edges[-1]:g} mm")
        except (Missing, ValueError) as ex:
            fails.append(str(ex))
    return (f"max (Σ bins − total)/se {worst_z:.2f}, worst r99 rel. {worst_r99:.1e}, "
            f"min (r_max − r99) {margin:.3g} mm"), fails


def noise_l1(se_rgb, rd_rgb, edges, r99) -> np.ndarray:
    """The fit error a perfect fit would show from the table's own noise: the energy-weighted
    relative L1 of independent normal errors, E|N(0, se)| = se sqrt(2/pi), over the same bins
    as fit_error. A fit error is |fit - table| <= |fit - truth| + |noise|, so a threshold on
    the model's error is max_error + this."""
    a = edges[:-1]
    area = areas(edges)
    out = np.zeros(3)
    for c in range(3):
        m = a < r99[c]
        den = np.sum(rd_rgb[m, c] * area[m])
        out[c] = math.sqrt(2 / math.pi) * np.sum(se_rgb[m, c] * area[m]) / den if den > 0 else np.inf
    return out


def check_fit(bk: Bake, entries: list[str], max_error, thresholds: bool) -> tuple[str, list[str]]:
    fails, worst_d, worst = [], 0.0, np.zeros(3)
    worst_excess = np.full(3, -np.inf)
    for e in entries:
        try:
            var, w = bk.get(e, "gaussians/variance_mm2"), bk.get(e, "gaussians/weight_rgb")
            got = bk.get(e, "gaussians/error_rgb")
            if not (np.all(np.isfinite(var)) and np.all(var > 0)):
                fails.append(f"{e}: /{e}/gaussians/variance_mm2 not all > 0: {var}")
                continue
            if not (np.all(np.isfinite(w)) and np.all(w >= 0)):
                fails.append(f"{e}: /{e}/gaussians/weight_rgb has negative/non-finite weights (min {np.min(w):.3g})")
            err = fit_error(var, w, bk.get(e, "rd_rgb_per_mm2"), bk.get(e, "r_edges_mm"), bk.get(e, "r99_mm"))
            d = rel(got, err, 1.0)
            worst_d, worst = max(worst_d, d), np.maximum(worst, err)
            if not d <= TOL_FIT:
                fails.append(f"{e}: /{e}/gaussians/error_rgb = {got} but recomputed {err} (|Δ| {d:.3g} > {TOL_FIT:g})")
            noise = noise_l1(bk.get(e, "rd_rgb_per_mm2_se"), bk.get(e, "rd_rgb_per_mm2"),
                             bk.get(e, "r_edges_mm"), bk.get(e, "r99_mm"))
            worst_excess = np.maximum(worst_excess, err - noise)
            if thresholds and np.any(err > max_error + noise):
                fails.append(f"{e}: fit error {np.round(err, 4)} exceeds --max-error {max_error} "
                             f"+ the table's own noise {np.round(noise, 4)}")
        except (Missing, ValueError) as ex:
            fails.append(str(ex))
    lim = (f" (limits {','.join(f'{m:g}' for m in max_error)} + the table's noise)" if thresholds
           else " (thresholds not applied)")
    return (f"worst error R,G,B {worst[0]:.4f},{worst[1]:.4f},{worst[2]:.4f}; worst error beyond noise "
            f"{','.join(f'{x:.4f}' for x in worst_excess)}{lim}; |Δ error_rgb| {worst_d:.1e}"), fails


def as_comparable(a):
    a = np.asarray(a)
    if a.dtype.kind in "SO":
        return np.vectorize(text, otypes=[object])(a) if a.size else a.astype(object)
    return a


def check_bkt(bk: Bake, path: Path) -> tuple[str, list[str]]:
    if not path.exists():
        return "", [f"{path.name} missing"]
    try:
        import bkt  # validation/bkt.py
    except ImportError as ex:
        return "", [f"cannot import validation/bkt.py: {ex}"]
    try:
        kind, _meta, arrays = bkt.read_bkt(str(path))
    except Exception as ex:  # noqa: BLE001 - any reader error is a FAIL of this check
        return "", [f"{path.name}: cannot be read by validation/bkt.py: {type(ex).__name__}: {ex}"]
    fails, n = [], 0
    for name in bk.dataset_paths():
        if name not in arrays:
            fails.append(f"dataset {name} missing from {path.name}")
            continue
        a, b = as_comparable(bk.data[name]), as_comparable(arrays[name])
        n += 1
        if a.shape != b.shape:
            fails.append(f"{name}: shape {b.shape} in .bkt, {a.shape} in .h5")
        elif not np.array_equal(a, b, equal_nan=a.dtype.kind == "f" and b.dtype.kind == "f"):
            fails.append(f"{name}: values differ (.bkt {b.dtype}, .h5 {a.dtype}; "
                         f"max |Δ| {np.max(np.abs(a.astype(float) - b.astype(float))) if a.dtype.kind in 'fiu' else '?'})")
    return f"kind {kind!r}, {n} datasets compared, {len(arrays)} arrays in file", fails


def check_exr(bk: Bake, path: Path, order: list[str]) -> tuple[str, list[str]] | None:
    if not path.exists():
        return None
    import OpenEXR
    with OpenEXR.File(str(path), separate_channels=True) as f:
        hdr, ch = f.header(), {k: np.asarray(v.pixels) for k, v in f.channels().items()}
    if "entries" in hdr:
        s = text(hdr["entries"])
        try:
            order = [text(x) for x in json.loads(s)]
        except ValueError:
            order = [x.strip() for x in s.replace(",", "\n").splitlines() if x.strip()]
    fails = [f"channel {c} missing (have {sorted(ch)})" for c in ("R", "G", "B", "r_mm") if c not in ch]
    if fails:
        return "", fails
    h, w = ch["R"].shape
    if h != len(order):
        fails.append(f"{h} rows but {len(order)} entries")
    worst = 0.0
    for row, e in enumerate(order[:h]):
        try:
            rgb, r = bk.get(e, "rd_rgb_per_mm2").astype(np.float32), bk.get(e, "r_mm").astype(np.float32)
        except Missing as ex:
            fails.append(f"row {row}: {ex}")
            continue
        nr = len(r)
        if nr > w:
            fails.append(f"{e}: {nr} radial bins but the image is {w} wide")
            continue
        for c, ref in (("R", rgb[:, 0]), ("G", rgb[:, 1]), ("B", rgb[:, 2]), ("r_mm", r)):
            got = ch[c][row, :nr].astype(np.float64)
            d = rel(got, ref.astype(np.float64), float(np.max(np.abs(ref))) or 1e-300)
            worst = max(worst, d)
            if not d <= 1e-6:
                fails.append(f"{e} (row {row}) channel {c}: max deviation from float32 table {d:.3g} of max")
    return f"{h}x{w}, channels {sorted(ch)}, worst {worst:.1e}", fails


def sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def check_manifest(bk: Bake, d: Path, man: dict, entries: list[str]) -> tuple[str, list[str]]:
    fails = []
    names = [m.get("name") for m in man.get("entries", [])]
    if sorted(names) != sorted(entries) or len(set(names)) != len(names):
        fails.append(f"manifest entries {names} differ from the HDF5 entry groups {entries}")
    for m in man.get("entries", []):
        if m.get("name") in entries and "params_json" in bk.attrs.get(m["name"], {}):
            if m.get("params") != json.loads(text(bk.attrs[m["name"]]["params_json"])):
                fails.append(f"{m['name']}: manifest params differ from params_json")
    listed = set()
    for rec in man.get("files", []):
        p = rec.get("path", "")
        listed.add(p)
        full = (d / p).resolve()
        if Path(p).is_absolute() or d.resolve() not in full.parents:
            fails.append(f"file {p!r}: path is not relative to the spec directory")
        elif not full.is_file():
            fails.append(f"file {p}: listed but missing")
        elif full.stat().st_size != rec.get("bytes"):
            fails.append(f"file {p}: {full.stat().st_size} bytes, manifest says {rec.get('bytes')}")
        elif sha256(full) != rec.get("sha256"):
            fails.append(f"file {p}: sha256 differs from the manifest")
    required = ["profiles.h5", "profiles.bkt"] + (["profiles_rgb.exr"] if (d / "profiles_rgb.exr").exists() else [])
    fails += [f"{p} not listed in manifest files" for p in required if p not in listed]
    on_disk = {str(p.relative_to(d)) for p in d.rglob("*") if p.is_file()} - {"manifest.json"}
    unlisted = sorted(on_disk - listed)
    sheets = list((d / "preview").glob("contact_sheet*.png"))
    if not sheets:
        fails.append("no preview/contact_sheet*.png")
    for p in sheets + [d / "preview" / "profiles" / f"{e}.png" for e in entries]:
        if not p.is_file() or p.read_bytes()[:8] != b"\x89PNG\r\n\x1a\n":
            fails.append(f"{p.relative_to(d)} missing or not a PNG")
    note = f"; not listed: {unlisted}" if unlisted else ""
    return f"{len(listed)} files verified, {len(sheets)} contact sheet(s){note}", fails


def check_rerun(bk: Bake, d: Path, bake_fn) -> tuple[str, list[str]]:
    with tempfile.TemporaryDirectory(prefix="check_profiles_rerun_") as tmp:
        d2 = bake_fn(Path(tmp))
        fails = []
        for f in ("profiles.bkt", "profiles_rgb.exr", "manifest.json"):
            if (d / f).exists() and (d / f).read_bytes() != (d2 / f).read_bytes():
                fails.append(f"{f} differs byte-wise between the two runs")
        bk2 = Bake(d2 / "profiles.h5")
        for name in sorted(set(bk.data) | set(bk2.data)):
            a, b = bk.data.get(name), bk2.data.get(name)
            if a is None or b is None or not np.array_equal(as_comparable(a), as_comparable(b)):
                fails.append(f"HDF5 dataset {name} differs between the two runs")
        for g in sorted(set(bk.attrs) | set(bk2.attrs)):
            if {k: text(v) for k, v in bk.attrs.get(g, {}).items()} != \
               {k: text(v) for k, v in bk2.attrs.get(g, {}).items()}:
                fails.append(f"HDF5 attributes of /{g} differ between the two runs")
    return f"{len(bk.data)} datasets compared", fails


# ---------------------------------------------------------------- driver

def build_baker() -> Path:
    print("building: cargo build --release -q -p baker", flush=True)
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "baker"], cwd=REPO, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return (target if target.is_absolute() else REPO / target) / "release" / "baker"


def spec_dir(out: Path, spec: Path | None) -> Path:
    if (out / "profiles.h5").exists():
        return out
    if spec is not None:
        return out / spec.stem
    subs = [p for p in out.iterdir() if (p / "profiles.h5").exists()] if out.is_dir() else []
    if len(subs) != 1:
        sys.exit(f"{out}: no profiles.h5 in it or in exactly one sub-directory (give --spec)")
    return subs[0]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baker", help="baker binary (default: cargo build --release, target/release/baker)")
    ap.add_argument("--spec", help="spec file to bake (e.g. tests/specs/profiles_small.yaml)")
    ap.add_argument("--photons", type=int, help="photons per simulation (passed to the baker)")
    ap.add_argument("--out", help="check this existing bake directory instead of baking")
    ap.add_argument("--keep", metavar="DIR", help="bake into DIR and keep it (default: a temp dir)")
    ap.add_argument("--fit-thresholds", action="store_true", help="FAIL if a Gaussian fit error exceeds --max-error")
    ap.add_argument("--max-error", default="0.05,0.03,0.03", help="fit error limits R,G,B (default 0.05,0.03,0.03)")
    ap.add_argument("--rerun", action="store_true", help="bake again and require identical outputs")
    ap.add_argument("--timeout", type=float, default=3600, help="seconds allowed per bake (default 3600)")
    args = ap.parse_args()
    max_error = np.array([float(x) for x in args.max_error.split(",")])
    if max_error.shape != (3,):
        ap.error("--max-error needs three comma-separated numbers")
    spec = Path(args.spec).resolve() if args.spec else None
    if (args.out is None or args.rerun) and spec is None:
        ap.error("--spec is needed to bake (without --out, or with --rerun)")
    baker = None

    def bake(out: Path) -> Path:
        nonlocal baker
        if baker is None:
            baker = Path(args.baker).resolve() if args.baker else build_baker()
        cmd = [str(baker), "bake", str(spec), "--out", str(out), "--quiet"]
        cmd += ["--photons", str(args.photons)] if args.photons else []
        print("running:", " ".join(cmd), flush=True)
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=args.timeout)
        if p.returncode != 0:
            sys.exit(f"baker failed (exit {p.returncode}):\n{p.stderr[-4000:]}")
        return out / spec.stem

    tmp = None
    try:
        if args.out:
            d = spec_dir(Path(args.out), spec)
        else:
            if args.keep:
                Path(args.keep).mkdir(parents=True, exist_ok=True)
                root = Path(args.keep)
            else:
                tmp = tempfile.TemporaryDirectory(prefix="check_profiles_")
                root = Path(tmp.name)
            d = bake(root.resolve())
        print(f"checking {d}")
        if not (d / "profiles.h5").exists():
            print(f"FAIL layout: {d / 'profiles.h5'} missing")
            return 1
        bk = Bake(d / "profiles.h5")
        man = json.loads((d / "manifest.json").read_text()) if (d / "manifest.json").exists() else None
        order = [m.get("name") for m in man.get("entries", [])] if man else []
        entries = order if sorted(order) == sorted(bk.groups) else sorted(bk.groups)

        results = []

        def run(name, fn, *a):
            try:
                res = fn(*a)
            except (Missing, ValueError, KeyError, OSError, subprocess.SubprocessError) as ex:
                res = ("", [f"{type(ex).__name__}: {ex}"])
            if res is None:
                print(f"SKIP {name}: file absent")
                return
            summary, fails = res
            results.append(not fails)
            print(f"{'PASS' if not fails else 'FAIL'} {name}: {summary}" if summary or not fails else f"FAIL {name}")
            for f in fails[:SHOW]:
                print(f"    {f}")
            if len(fails) > SHOW:
                print(f"    ... and {len(fails) - SHOW} more")

        run("layout", check_layout, bk, entries, args.photons)
        run("1 colour (colour-science, D65 / CIE 1931 2° / sRGB)", check_colour, bk, entries)
        run("2 rgb profiles and SE propagation", check_rgb, bk, entries)
        run("3 energy and r99", check_energy, bk, entries)
        run("4 gaussian fit", check_fit, bk, entries, max_error, args.fit_thresholds)
        run("5 profiles.bkt == profiles.h5", check_bkt, bk, d / "profiles.bkt")
        run("6 exr", check_exr, bk, d / "profiles_rgb.exr", entries)
        if man is None:
            print("FAIL 7 manifest: manifest.json missing")
            results.append(False)
        else:
            run("7 manifest and previews", check_manifest, bk, d, man, entries)
        if args.rerun:
            if args.photons is None and "photons" in bk.root:
                args.photons = int(bk.root["photons"])
            run("8 determinism (--rerun)", check_rerun, bk, d, bake)
    finally:
        if tmp is not None:
            tmp.cleanup()
    n_fail = results.count(False)
    print(f"check_profiles: {len(results) - n_fail} passed, {n_fail} failed")
    return 1 if n_fail else 0


if __name__ == "__main__":
    sys.exit(main())
