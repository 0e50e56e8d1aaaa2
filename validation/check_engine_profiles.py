#!/usr/bin/env python3
"""How faithful is each engine's skin? Cycles (the `--to blender` export) and Mitsuba 3 (the
`--to mitsuba` export) render a thick slab of the exported skin; the radial profile read from
the renders is compared with the baked Rd(r) (issue 19, item 4).

    python3 validation/check_engine_profiles.py --quick -o /tmp/engine_profiles   # CI, < 2 min
    python3 validation/check_engine_profiles.py --full  -o out/engine_profiles    # the database

--quick bakes validation/specs/engine_profiles.yaml (four entries, types I, III, IV, VI at age
30, xi 0.5; 7 wavelengths, 1e5 photons) into DIR/bake; --full reads out/fitzpatrick/profiles.bkt
(the same four entries of the database) unless --table says otherwise. Blender runs in the bpy
venv (validation/blender/venv.sh, default target/bpy-venv/bin/python); --no-cycles skips it.
Writes DIR/engine_profiles.md, DIR/engine_profiles.json and DIR/engine_profiles.png (engine vs
baked Rd(r), log-log, per entry and channel); renders and exports stay in DIR/work.

What is rendered, and why it measures Rd(r)
-------------------------------------------
Rd(r) (mm^-2) is the flux leaving the surface per unit area at distance r from a normally
incident pencil beam, per unit beam power, integrated over all exit directions. A camera sees
one exit direction only, so imaging a beam spot needs the (engine-dependent, unknown) angular
distribution of the exiting light: pi L / E is exact only for a Lambertian exit, and for the
index-matched Mitsuba medium the exit radiance follows Chandrasekhar's H(mu) (about +26 % at
normal exit for albedo near 1). Reciprocity removes that assumption. With the BSSRDF
S(xo, wo; xi, wi) (dLo = S dPhi_i) and S(xo, wo; xi, wi) = S(xi, wi; xo, wo),

    Rd(|x - y|) = integral over the hemisphere of S(x, w; y, n) cos(theta) dw,

so a surface patch A lit from its whole hemisphere by uniform radiance Le, seen along the
normal n at the point y, has exit radiance L(y, n) = Le * integral over A of Rd(|x - y|) dA.
Each annulus a_k <= r < a_(k+1) around the camera's point is therefore lit alone, by a
Lambertian emitter ring of radiance Le lying eps above the surface (invisible to the camera and
to glossy rays), and the orthographic camera looking straight down at the ring centre reads

    E_k = L / Le = integral over the annulus of Rd(r) 2 pi r dr   (the ring's energy, no units).

No Fresnel, cosine or pi factor enters: the engine's own boundary (Cycles' specular layer and
BSSRDF, Mitsuba's null boundary) acts on both ends as it would for a real beam. Le is measured,
not assumed: the same camera over a white Lambertian slab (albedo 1, Rd = delta at r = 0) under
one disk as wide as the slab reads Le (Cycles' Emission strength 1 and Mitsuba's radiance 1
both read 1 within 0.2 %; the measured value is used). The ring's height h spreads its light
by about h beyond its edges, at grazing incidence, without changing its total flux; grazing
light enters shallower and reflects more, so h must stay small against the ring widths: with
h = 1 % of the ring's radius Mitsuba's totals came out 2-4 % high, with h = 0.1 % within 1 %.
Cycles (no ray offsets since Blender 3.2) uses one flat height eps = 2.5e-5 max r99; Mitsuba
(single-precision offsets of about 9e-5 (1 + |p|) scene units) works in micrometres with
h = 1e-3 x each ring's outer radius (engines/mitsuba_rings.py), and the exported medium's
`scale` divided by 1000 as the export's comment prescribes for other units. The camera
averages over a square of side a_1 / 5 around the centre; rings are polygons of 256 sides
with the circle's area.

The baked energy per ring is exact for the table's histogram (Rd constant in each table bin):
B_k = C(a_(k+1)) - C(a_k), C(r) = sum of Rd_i pi (min(r, e_(i+1))^2 - e_i^2)^+.

Comparison (per engine, entry, channel c)
    r99_c  the radius holding 99 % of the baked profile's energy in channel c (from the
           histogram, linear in the cumulative energy; equals the table's r99_mm); every
           channel's r99 is a ring edge.
    L1_c   = sum over rings inside r99_c of |E_k - B_k| / sum of B_k: the energy-weighted
           relative L1, integral of |Rd_engine - Rd_baked| 2 pi r dr / integral of
           Rd_baked 2 pi r dr over r < r99_c, at the rings' resolution (6 rings per decade in
           --quick, 10 in --full, between a_1 = max(min r99 / 30, 10 eps) and max r99).
    shape_c the same L1 after scaling the engine's rings to the baked energy inside r99_c
           (profile shape only; L1_c also counts the albedo difference)
    energy_c = sum E_k / sum B_k inside r99_c; total_c = all rings out to the slab's edge
           (2.5 max r99; the slab is as thick), the engine's total diffuse reflectance.
    noise_c = sqrt(2/pi) sum sigma_k / sum B_k, sigma_k^2 = the render's standard error^2
           (from S independent seeds) + the bake's (rd_rgb_per_mm2_se): the expected L1 of a
           render that matched the table exactly. L1 well above it is signal.

Checks (a FAIL exits with status 1), all sound without a threshold on the L1 itself:
  * every ring finite and every channel's total positive, for every engine;
  * the calibration Le within 1 % of 1 (Cycles: Emission strength 1; Mitsuba: radiance 1);
  * the Blender material's Subsurface Method is the one the export script names;
  * the measurement: Cycles' Christensen-Burley closure renders the analytic Burley profile
    of the export's fit (intern/cycles/kernel/closure/bssrdf.h, bssrdf_burley_eval), so its
    rings must match A (F(b) - F(a)) within 3 x its noise L1 + 0.03 (ring-height blur, camera
    footprint; measured 0.008-0.017 in --full, 0.013-0.024 in --quick; a 20 % error in the
    export's Subsurface Scale gives 0.11 and fails);
  * total reflectance = the exported Burley A within 5 standard errors + 3 % for Mitsuba
    (the export makes its albedo give A for a semi-infinite index-matched medium; 3 %: the
    slab's finite size and single-precision ray offsets, which the export documents at 8 %
    for a cube 2000 mean free paths wide, ours < 400) and for Cycles' Christensen-Burley
    (A by construction: Base Color = A / (1 - F0)).
The L1 numbers against the table are reported, not thresholded: the exports are fits, and how
far each engine lands from the table is what this check measures. Random-walk methods have no
exact albedo relation to A, so their totals are reported only.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
import zlib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "validation"))
sys.path.insert(0, str(ROOT / "validation" / "engines"))

from bkt import read_bkt  # noqa: E402

ENTRIES = ["typeI_age30_xi0.5", "typeIII_age30_xi0.5", "typeIV_age30_xi0.5", "typeVI_age30_xi0.5"]
CHANNELS = "RGB"
METHODS = ["burley", "random-walk", "random-walk-skin"]

MODES = {
    # rings per decade, camera pixels per side, samples per pixel per seed, seeds
    "quick": {"per_decade": 6, "pixels": 4, "mitsuba_spp": 256, "cycles_spp": 256, "seeds": 4},
    "full": {"per_decade": 10, "pixels": 4, "mitsuba_spp": 2048, "cycles_spp": 2048, "seeds": 4},
}


def fail(msg):
    raise SystemExit(f"error: {msg}")


def write_atomic(path: Path, data):
    tmp = path.with_name(path.name + ".tmp")
    if isinstance(data, bytes):
        tmp.write_bytes(data)
    else:
        tmp.write_text(data, encoding="utf-8")
    os.replace(tmp, path)


# ---------------------------------------------------------------------------------------------
# Baked table


class Baked:
    """One entry's histogram Rd (per mm^2, linear sRGB) on r_edges_mm, with its standard error."""

    def __init__(self, arrays, name):
        try:
            self.edges = np.asarray(arrays[f"{name}/r_edges_mm"], float)
            self.rd = np.asarray(arrays[f"{name}/rd_rgb_per_mm2"], float)
            self.se = np.asarray(arrays[f"{name}/rd_rgb_per_mm2_se"], float)
            self.albedo = np.asarray(arrays[f"{name}/albedo_rgb"], float)
            self.r99_table = np.asarray(arrays[f"{name}/r99_mm"], float)
        except KeyError as e:
            fail(f"table has no entry {name!r} (missing {e})")
        self.area = np.pi * (self.edges[1:] ** 2 - self.edges[:-1] ** 2)
        cum = np.vstack([np.zeros(3), np.cumsum(self.rd * self.area[:, None], axis=0)])
        self.cum = cum  # energy inside each table edge, (bins + 1, 3)
        total = cum[-1]
        self.r99 = np.array([np.interp(0.99, cum[:, c] / total[c], self.edges) for c in range(3)])

    def ring_energy(self, a):
        """Energy of each ring [a_k, a_(k+1)) and its standard error, (rings, 3) each."""
        a = np.asarray(a, float)
        lo, hi = self.edges[:-1], self.edges[1:]
        # Overlap area of every ring with every table bin, (rings, bins).
        r0 = np.clip(a[:-1, None], lo[None, :], hi[None, :])
        r1 = np.clip(a[1:, None], lo[None, :], hi[None, :])
        w = np.pi * (r1**2 - r0**2)
        e = w @ self.rd
        se = np.sqrt((w**2) @ (self.se**2))
        return e, se


# ---------------------------------------------------------------------------------------------
# Geometry


EPS_REL = 2.5e-5  # Cycles: ring height above the surface / max r99 (Mitsuba: mitsuba_rings.py)


def geometry(baked: Baked, mode, eps_rel=EPS_REL):
    r99 = baked.r99
    r_max = float(r99.max())
    eps = eps_rel * r_max
    a1 = max(float(r99.min()) / 30.0, 10.0 * eps)
    n = max(2, int(math.ceil(MODES[mode]["per_decade"] * math.log10(r_max / a1))))
    edges = set(np.geomspace(a1, r_max, n + 1).tolist()) | set(r99.tolist())
    edges = sorted(edges)
    # Drop grid edges within 2 % of a channel's r99 (no sliver rings); r99s always stay.
    def is_r99(x):
        return any(abs(x - r) <= 1e-12 * r for r in r99)

    keep = [0.0]
    for e in edges:
        if keep[-1] > 0 and e / keep[-1] < 1.02 and not (is_r99(e) and is_r99(keep[-1])):
            if is_r99(e):
                keep[-1] = e
            continue
        keep.append(e)
    half = 2.5 * r_max
    keep.append(half)  # the tail ring, out to the slab's edge
    return {
        "edges_mm": keep,
        "eps_mm": eps,
        "slab_half_mm": half,
        "slab_thick_mm": half,
        "camera_footprint_mm": a1 / 5.0,
        "pixels": MODES[mode]["pixels"],
        "r99_mm": r99.tolist(),
    }


# ---------------------------------------------------------------------------------------------
# Exports


def run_cmd(cmd, what):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"{what} failed ({p.returncode}): {' '.join(map(str, cmd))}\n{p.stderr[-4000:]}")
    return p, time.perf_counter() - t0


def export_methods(baker):
    """Blender export methods the baker offers (`--method`), or [None] if it has no flag."""
    p, _ = run_cmd([baker, "export", "--help"], "baker export --help")
    if "--method" not in p.stdout:
        return [None]
    return [m for m in METHODS if m in p.stdout] or [None]


def mitsuba_ids(xml_path):
    """{entry name: medium id} from the `--to mitsuba` file (the comment before each medium
    starts with the entry's name)."""
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    root = ET.parse(xml_path, parser=parser).getroot()
    ids, last = {}, None
    for el in root:
        if el.tag is ET.Comment:
            last = el.text.strip().split(":")[0]
        elif el.tag == "medium" and last is not None:
            ids[last] = el.get("id")
    return ids


def blender_method_of(script_text):
    """Subsurface Method the export script sets (its METHOD constant, or a literal)."""
    m = re.search(r'^METHOD\s*=\s*"([A-Z_]+)"', script_text, re.M) or re.search(
        r'subsurface_method\s*=\s*"([A-Z_]+)"', script_text
    )
    return m.group(1) if m else "?"


# ---------------------------------------------------------------------------------------------
# Reading renders


def read_exr_rings(path, names):
    """Mean RGB of the light-group passes Combined_<name> of a Cycles multilayer EXR."""
    import OpenEXR

    out = {}
    with OpenEXR.File(str(path), separate_channels=False) as f:
        for part in f.parts:
            for cname, ch in part.channels.items():
                for n in names:
                    if cname.endswith(f"Combined_{n}"):
                        px = np.asarray(ch.pixels, float)
                        out[n] = px.reshape(-1, px.shape[-1])[:, :3].mean(axis=0)
                if cname.endswith(".Combined") or cname == "Combined":
                    px = np.asarray(ch.pixels, float)
                    out["__combined__"] = px.reshape(-1, px.shape[-1])[:, :3].mean(axis=0)
    missing = [n for n in names if n not in out]
    if missing:
        fail(f"{path}: no light-group pass for {missing}")
    return out


# ---------------------------------------------------------------------------------------------
# Comparison


def burley_rings(edges, a_rgb, d_rgb):
    """Ring energies of the Burley fit R(r) = A (e^(-r/d) + e^(-r/3d)) / (8 pi d r):
    A (F(b) - F(a)), F(r) = 1 - e^(-r/d)/4 - 3 e^(-r/3d)/4 (Christensen & Burley 2015)."""
    r = np.asarray(edges, float)[:, None]
    d = np.asarray(d_rgb, float)[None, :]
    F = 1 - np.exp(-r / d) / 4 - 3 * np.exp(-r / (3 * d)) / 4
    return np.asarray(a_rgb, float)[None, :] * np.diff(F, axis=0)


def compare(E_seeds, cal, baked: Baked, geom, fit):
    """E_seeds: (rings, seeds, 3) radiance per ring and seed; cal: (3,) calibration radiance;
    fit: {"A_rgb", "d_mm_rgb"} of the export's Burley fit."""
    export_a = fit["A_rgb"]
    E_seeds = np.asarray(E_seeds, float) / np.asarray(cal, float)[None, None, :]
    S = E_seeds.shape[1]
    E = E_seeds.mean(axis=1)
    se = E_seeds.std(axis=1, ddof=1) / math.sqrt(S) if S > 1 else np.full_like(E, np.nan)
    edges = np.asarray(geom["edges_mm"])
    B, B_se = baked.ring_energy(edges)
    Fb = burley_rings(edges, fit["A_rgb"], fit["d_mm_rgb"])
    per = {}
    for c, ch in enumerate(CHANNELS):
        inside = edges[1:] <= baked.r99[c] * (1 + 1e-9)
        e, b = E[inside, c], B[inside, c]
        sig = np.sqrt(se[inside, c] ** 2 + B_se[inside, c] ** 2)
        eb = b.sum()
        scale = eb / e.sum() if e.sum() > 0 else float("nan")
        f = Fb[inside, c]
        per[ch] = {
            "l1": float(np.abs(e - b).sum() / eb),
            # The same L1 of the Burley fit against the table (the export's fit error, at the
            # rings' resolution), and of the render against the fit: does the engine render
            # what the export meant? (noise: the render's alone)
            "fit_l1": float(np.abs(f - b).sum() / eb),
            "vs_fit_l1": float(np.abs(e - f).sum() / f.sum()),
            "vs_fit_noise_l1": float(math.sqrt(2 / math.pi) * se[inside, c].sum() / f.sum()),
            "shape_l1": float(np.abs(e * scale - b).sum() / eb),
            "noise_l1": float(math.sqrt(2 / math.pi) * sig.sum() / eb),
            "energy_ratio": float(e.sum() / eb),
            "total": float(E[:, c].sum()),
            "total_se": float(math.sqrt((se[:, c] ** 2).sum())),
            "baked_albedo": float(baked.albedo[c]),
            "export_A": float(export_a[c]) if export_a is not None else None,
            "r99_mm": float(baked.r99[c]),
            "rings_inside_r99": int(inside.sum()),
        }
    return {
        "channels": per,
        "ring_energy": E.tolist(),
        "ring_energy_se": se.tolist(),
        "baked_ring_energy": B.tolist(),
        "baked_ring_energy_se": B_se.tolist(),
        "calibration": list(map(float, cal)),
    }


# ---------------------------------------------------------------------------------------------
# Plot: plain numpy raster, written as PNG with zlib


def png_bytes(img):
    h, w, _ = img.shape
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(h))

    def chunk(tag, data):
        c = tag + data
        return len(data).to_bytes(4, "big") + c + zlib.crc32(c).to_bytes(4, "big")

    hdr = w.to_bytes(4, "big") + h.to_bytes(4, "big") + bytes([8, 2, 0, 0, 0])
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", hdr) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")


def draw_line(img, x0, y0, x1, y1, col, width=1):
    n = int(max(abs(x1 - x0), abs(y1 - y0))) + 1
    xs = np.linspace(x0, x1, n).round().astype(int)
    ys = np.linspace(y0, y1, n).round().astype(int)
    h, w, _ = img.shape
    for dx in range(-(width // 2), width - width // 2):
        for dy in range(-(width // 2), width - width // 2):
            xx, yy = xs + dx, ys + dy
            ok = (xx >= 0) & (xx < w) & (yy >= 0) & (yy < h)
            img[yy[ok], xx[ok]] = col


def draw_marker(img, x, y, col, kind, size=3):
    h, w, _ = img.shape
    x, y = int(round(x)), int(round(y))
    for dx in range(-size, size + 1):
        for dy in range(-size, size + 1):
            on = {
                "square": max(abs(dx), abs(dy)) == size,
                "cross": abs(dx) == abs(dy),
                "plus": dx == 0 or dy == 0,
                "diamond": abs(dx) + abs(dy) == size,
            }[kind]
            if on and 0 <= x + dx < w and 0 <= y + dy < h:
                img[y + dy, x + dx] = col

# 3 x 5 pixel glyphs (rows top to bottom, '#' = ink) for the plot's labels.
GLYPHS = {
    "0": ["###", "#.#", "#.#", "#.#", "###"], "1": [".#.", "##.", ".#.", ".#.", "###"],
    "2": ["###", "..#", "###", "#..", "###"], "3": ["###", "..#", ".##", "..#", "###"],
    "4": ["#.#", "#.#", "###", "..#", "..#"], "5": ["###", "#..", "###", "..#", "###"],
    "6": ["###", "#..", "###", "#.#", "###"], "7": ["###", "..#", ".#.", ".#.", ".#."],
    "8": ["###", "#.#", "###", "#.#", "###"], "9": ["###", "#.#", "###", "..#", "###"],
    ".": ["...", "...", "...", "...", ".#."], "-": ["...", "...", "###", "...", "..."],
    "e": ["...", "###", "#.#", "##.", "###"], " ": ["...", "...", "...", "...", "..."],
    "R": ["##.", "#.#", "##.", "#.#", "#.#"], "G": ["###", "#..", "#.#", "#.#", "###"],
    "B": ["##.", "#.#", "##.", "#.#", "##."], "I": ["###", ".#.", ".#.", ".#.", "###"],
    "V": ["#.#", "#.#", "#.#", "#.#", ".#."], "m": ["...", "##.", "###", "#.#", "#.#"],
    "r": ["...", "##.", "#..", "#..", "#.."], "d": ["..#", "..#", "###", "#.#", "###"],
    "t": [".#.", "###", ".#.", ".#.", ".##"], "y": ["#.#", "#.#", "###", "..#", "###"],
    "p": ["...", "###", "#.#", "###", "#.."], "^": [".#.", "#.#", "...", "...", "..."],
    "=": ["...", "###", "...", "###", "..."], "(": [".#.", "#..", "#..", "#..", ".#."],
    ")": [".#.", "..#", "..#", "..#", ".#."], "/": ["..#", "..#", ".#.", "#..", "#.."],
}


def draw_text(img, x, y, text, col=(0, 0, 0), scale=2, anchor="left"):
    """Draws `text` with its top at y; anchor left/right/centre at x."""
    w = len(text) * 4 * scale
    x0 = int(round(x - (w if anchor == "right" else w / 2 if anchor == "centre" else 0)))
    h, wd, _ = img.shape
    for i, ch in enumerate(text):
        g = GLYPHS.get(ch, GLYPHS[" "])
        for gy, row in enumerate(g):
            for gx, px in enumerate(row):
                if px == "#":
                    yy, xx = int(y) + gy * scale, x0 + (i * 4 + gx) * scale
                    if 0 <= yy and yy + scale <= h and 0 <= xx and xx + scale <= wd:
                        img[yy : yy + scale, xx : xx + scale] = col


def decade_label(d):
    return {-3: "0.001", -2: "0.01", -1: "0.1", 0: "1", 1: "10", 2: "100"}.get(d, f"1e{d}")


ENGINE_STYLE = [((220, 40, 40), "square"), ((30, 120, 220), "cross"), ((20, 160, 60), "plus"), ((170, 60, 200), "diamond")]


def plot(results, geoms, entries, engines, path: Path):
    """Grid: a row per entry, a column per channel. Axes log r (mm) x log Rd (mm^-2), a grid
    line per decade (darker at 1 mm and at Rd = 1 mm^-2); black line: baked (ring averages);
    markers: engines in the order of the legend in engine_profiles.md."""
    pw, ph, m, left, top = 300, 220, 40, 70, 40
    W, H = left + 3 * pw + 3 * m, top + len(entries) * (ph + m) + 10
    img = np.full((H, W, 3), 255, np.uint8)
    for i, ent in enumerate(entries):
        edges = np.asarray(geoms[ent]["edges_mm"])
        area = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
        rmid = np.sqrt(np.maximum(edges[:-1], edges[1] / 2) * edges[1:])
        rmid[0] = edges[1] / 2
        base = np.asarray(results[engines[0]][ent]["baked_ring_energy"]) / area[:, None]
        x_lo, x_hi = math.floor(math.log10(rmid[0])), math.ceil(math.log10(edges[-1]))
        for c in range(3):
            ox, oy = left + c * (pw + m), top + i * (ph + m)
            vals = [base[:, c]] + [np.asarray(results[e][ent]["ring_energy"])[:, c] / area for e in engines]
            pos = np.concatenate([v[v > 0] for v in vals])
            if pos.size == 0:
                continue  # an all-zero profile; reported as a failure by main()
            y_hi = math.ceil(math.log10(pos.max()))
            y_lo = max(math.floor(math.log10(pos.min())), y_hi - 6)

            def X(r):
                return ox + (math.log10(r) - x_lo) / (x_hi - x_lo) * (pw - 1)

            def Y(v):
                return oy + ph - 1 - (math.log10(v) - y_lo) / (y_hi - y_lo) * (ph - 1)

            img[oy : oy + ph, ox : ox + pw] = 250
            for d in range(x_lo, x_hi + 1):
                g = 150 if d == 0 else 215
                draw_line(img, X(10.0**d), oy, X(10.0**d), oy + ph - 1, (g, g, g))
                draw_text(img, X(10.0**d), oy + ph + 4, decade_label(d), anchor="centre")
            for d in range(y_lo, y_hi + 1):
                g = 150 if d == 0 else 215
                draw_line(img, ox, Y(10.0**d), ox + pw - 1, Y(10.0**d), (g, g, g))
                if (y_hi - d) % 2 == 0:
                    draw_text(img, ox - 4, Y(10.0**d) - 5, decade_label(d), anchor="right")
            label = ent.split("_")[0].replace("type", "t") + " " + CHANNELS[c]  # "tIV G"
            draw_text(img, ox + pw / 2, oy - 14, label, anchor="centre")
            if i == len(entries) - 1 and c == 1:
                draw_text(img, ox + pw / 2, oy + ph + 18, "r (mm)", anchor="centre")
            if c == 0 and i == 0:
                draw_text(img, 4, oy - 14, "Rd (/mm^2)")
            r99 = geoms[ent]["r99_mm"][c]
            draw_line(img, X(r99), oy, X(r99), oy + ph - 1, (240, 170, 0))
            pts = [(X(r), Y(v)) for r, v in zip(rmid, base[:, c]) if v > 10.0**y_lo]
            for (a, b), (p, q) in zip(pts[:-1], pts[1:]):
                draw_line(img, a, b, p, q, (0, 0, 0), width=2)
            for (col, kind), v in zip(ENGINE_STYLE, vals[1:]):
                for r, y in zip(rmid, v):
                    if y > 10.0**y_lo:
                        draw_marker(img, X(r), Y(y), col, kind)
            img[oy, ox : ox + pw] = img[oy + ph - 1, ox : ox + pw] = 0
            img[oy : oy + ph, ox] = img[oy : oy + ph, ox + pw - 1] = 0
    write_atomic(path, png_bytes(img))


# ---------------------------------------------------------------------------------------------


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--quick", action="store_true", help="CI mode (default): small bake, few samples")
    g.add_argument("--full", action="store_true", help="database table, more rings and samples")
    ap.add_argument("-o", "--out", required=True, help="output folder")
    ap.add_argument("--baker", default=str(ROOT / "target/release/baker"))
    ap.add_argument("--table", help="profiles.bkt (default: --quick bakes validation/specs/engine_profiles.yaml, --full reads out/fitzpatrick/profiles.bkt)")
    ap.add_argument("--entry", action="append", help=f"entries (default: {', '.join(ENTRIES)})")
    ap.add_argument("--bpy", default=str(ROOT / "target/bpy-venv/bin/python"), help="python with bpy")
    ap.add_argument("--no-cycles", action="store_true", help="skip Blender/Cycles")
    ap.add_argument("--seeds", type=int, help="independent renders per ring (default 4)")
    ap.add_argument("--spp", type=int, help="samples per pixel per seed, both engines")
    ap.add_argument("--eps-rel", type=float, default=EPS_REL, help=f"ring height / max r99 ({EPS_REL:g})")
    args = ap.parse_args()
    mode = "full" if args.full else "quick"
    cfg = dict(MODES[mode])
    if args.seeds:
        cfg["seeds"] = args.seeds
    if args.spp:
        cfg["mitsuba_spp"] = cfg["cycles_spp"] = args.spp
    if cfg["seeds"] < 2:
        fail("--seeds must be >= 2 (the standard error needs two renders)")
    out = Path(args.out)
    work = out / "work"
    work.mkdir(parents=True, exist_ok=True)
    baker = args.baker
    if not Path(baker).is_file():
        fail(f"no baker binary at {baker} (cargo build --release -p baker)")
    times = {}
    t_all = time.perf_counter()

    # Table
    if args.table:
        table = Path(args.table)
    elif mode == "full":
        table = ROOT / "out/fitzpatrick/profiles.bkt"
        if not table.is_file():
            fail(f"{table} does not exist: bake specs/fitzpatrick.yaml, or pass --table")
    else:
        _, times["bake_s"] = run_cmd(
            [baker, "bake", str(ROOT / "validation/specs/engine_profiles.yaml"), "-o", str(out / "bake")],
            "baker bake",
        )
        table = out / "bake/engine_profiles/profiles.bkt"
    _, _, arrays = read_bkt(str(table))
    entries = args.entry or ENTRIES
    baked = {e: Baked(arrays, e) for e in entries}
    geoms = {e: geometry(baked[e], mode, args.eps_rel) for e in entries}
    for e in entries:
        if not np.allclose(baked[e].r99, baked[e].r99_table, rtol=1e-6):
            fail(f"{e}: r99 from the histogram {baked[e].r99} != the table's {baked[e].r99_table}")

    # Exports
    sel = [x for e in entries for x in ("--entry", e)]
    mxml = work / "skin.mitsuba.xml"
    run_cmd([baker, "export", str(table), "--to", "mitsuba", "-q", "-o", str(mxml), *sel], "export mitsuba")
    burley_json = work / "skin.burley.json"
    run_cmd([baker, "export", str(table), "--to", "burley", "-q", "-o", str(burley_json), *sel], "export burley")
    fits = burley_fits(json.loads(burley_json.read_text(encoding="utf-8")), entries)
    ids = mitsuba_ids(mxml)
    methods = export_methods(baker)
    blender_scripts = {}
    for m in methods:
        p = work / f"skin.blender.{m or 'default'}.py"
        extra = ["--method", m] if m else []
        run_cmd([baker, "export", str(table), "--to", "blender", "-q", "-o", str(p), *extra, *sel], "export blender")
        blender_scripts[m] = p

    results, engine_info = {}, {}
    failures = []

    # Mitsuba
    import mitsuba_rings

    job = {
        "mitsuba_xml": str(mxml),
        "spp": cfg["mitsuba_spp"],
        "seeds": list(range(cfg["seeds"])),
        "entries": [{"id": ids[e], "geometry": geoms[e]} for e in entries],
    }
    t0 = time.perf_counter()
    mres = mitsuba_rings.run(job, str(work / "mitsuba"))
    times["mitsuba_s"] = time.perf_counter() - t0
    key = "Mitsuba 3 (homogeneous medium, volpathmis)"
    results[key] = {}
    import mitsuba as mi

    engine_info[key] = {"version": mi.__version__, "variant": mi.variant(), "spp_per_seed": cfg["mitsuba_spp"]}
    for e in entries:
        r = mres[ids[e]]
        results[key][e] = compare(r["ring_radiance"], r["calibration_radiance"], baked[e], geoms[e], fits[e])
        results[key][e]["seconds"] = r["seconds"]

    # Cycles
    if not args.no_cycles:
        if not Path(args.bpy).is_file():
            fail(f"no bpy python at {args.bpy} (bash validation/blender/venv.sh), or pass --no-cycles")
        cwork = work / "cycles"
        cwork.mkdir(exist_ok=True)
        runs = []
        for m in methods:
            for e in entries:
                runs.append(
                    {
                        "key": f"{m or 'default'}__{ids[e]}",
                        "blender_script": str(blender_scripts[m]),
                        "material": e,
                        "geometry": geoms[e],
                    }
                )
        cjob = {
            "seeds": list(range(cfg["seeds"])),
            "spp": cfg["cycles_spp"],
            "workdir": str(cwork),
            "result": str(cwork / "result.json"),
            "runs": runs,
        }
        jpath = cwork / "job.json"
        write_atomic(jpath, json.dumps(cjob, indent=1))
        t0 = time.perf_counter()
        run_cmd([args.bpy, str(ROOT / "validation/engines/cycles_rings.py"), str(jpath)], "Blender/Cycles")
        times["cycles_s"] = time.perf_counter() - t0
        cres = json.loads((cwork / "result.json").read_text(encoding="utf-8"))
        for m in methods:
            sm = blender_method_of(blender_scripts[m].read_text(encoding="utf-8"))
            key = f"Cycles, {sm} (`--to blender{' --method ' + m if m else ''}`)"
            results[key] = {}
            for e in entries:
                r = cres[f"{m or 'default'}__{ids[e]}"]
                names = r["ring_names"]
                rad = np.stack(
                    [np.stack([read_exr_rings(f, names)[n] for n in names]) for f in r["seed_files"]], axis=1
                )
                cal = read_exr_rings(r["calibration_file"], ["ring00"])["ring00"]
                results[key][e] = compare(rad, cal, baked[e], geoms[e], fits[e])
                results[key][e]["seconds"] = r["seconds"]
                if r["subsurface_method"] != sm:
                    failures.append(f"{key} {e}: Blender material has Subsurface Method {r['subsurface_method']}, the script says {sm}")
                results[key][e]["cycles_method"] = r["subsurface_method"]
                engine_info[key] = {
                    "version": f"Blender {r['blender_version']}",
                    "subsurface_method": sm,
                    "spp_per_seed": cfg["cycles_spp"],
                }

    times["total_s"] = time.perf_counter() - t_all

    # Checks
    for key, per in results.items():
        for e, r in per.items():
            E = np.asarray(r["ring_energy"])
            if not np.all(np.isfinite(E)):
                failures.append(f"{key} {e}: non-finite ring energy")
            cal = np.asarray(r["calibration"])
            if np.any(np.abs(cal - 1) > 0.01):
                failures.append(f"{key} {e}: calibration radiance {cal} not within 1 % of 1")
            for ch, c in r["channels"].items():
                if not c["total"] > 0:
                    failures.append(f"{key} {e} {ch}: total reflectance {c['total']} not positive")
                if r.get("cycles_method") == "BURLEY":
                    # The measurement itself: Cycles' Christensen-Burley closure is the analytic
                    # Burley profile of the fit (bssrdf.h bssrdf_burley_eval), so the rings must
                    # give it back, within noise plus the blur of the gap eps and of the camera
                    # footprint (<= 3 % of the energy inside r99 for the smallest d here).
                    tol = 3 * c["vs_fit_noise_l1"] + 0.03
                    if not c["vs_fit_l1"] <= tol:
                        failures.append(
                            f"{key} {e} {ch}: Cycles Burley vs its analytic profile L1 "
                            f"{c['vs_fit_l1']:.3f} > {tol:.3f}: the ring measurement is off"
                        )
                exact = key.startswith("Mitsuba") or r.get("cycles_method") == "BURLEY"
                if exact:
                    tol = 5 * c["total_se"] + 0.03 * c["export_A"]
                    dev = abs(c["total"] - c["export_A"])
                    c["total_vs_A_ok"] = bool(dev <= tol)
                    if dev > tol:
                        failures.append(
                            f"{key} {e} {ch}: total reflectance {c['total']:.4f} vs exported A "
                            f"{c['export_A']:.4f} (bound {tol:.4f})"
                        )

    report = {
        "mode": mode,
        "table": str(table),
        "entries": entries,
        "config": cfg,
        "engines": engine_info,
        "geometry": geoms,
        "times_s": times,
        "results": results,
        "failures": failures,
    }
    write_atomic(out / "engine_profiles.json", json.dumps(report, indent=1))
    write_atomic(out / "engine_profiles.md", markdown(report))
    plot(results, geoms, entries, list(results), out / "engine_profiles.png")
    print(markdown(report))
    for f in failures:
        print("FAIL", f)
    print(
        f"check_engine_profiles: {len(results)} engines x {len(entries)} entries, "
        f"{len(failures)} failures, {times['total_s']:.1f} s -> {out}"
    )
    return 1 if failures else 0


def burley_fits(doc, entries):
    """{entry: {"A_rgb", "d_mm_rgb"}} from the `--to burley` JSON (its "entries" list)."""
    found = {}
    for x in doc.get("entries", []):
        if x.get("name") in entries:
            found[x["name"]] = {"A_rgb": x["A_rgb"], "d_mm_rgb": x["d_mm_rgb"]}
    missing = [e for e in entries if e not in found]
    if missing:
        fail(f"Burley JSON has no (A, d) for {missing}")
    return found


def markdown(rep):
    lines = [
        "# Engine skin profiles vs the baked Rd(r)",
        "",
        f"Table `{rep['table']}` ({rep['mode']} mode). Per channel: **L1** = energy-weighted relative L1 of",
        "the rendered Rd(r) against the baked one inside that channel's r99; **fit L1** = the same for the",
        "export's Burley fit (A, d) against the table; **vs fit** = the render against that fit (relative",
        "to the fit's energy): does the engine render what the export meant; **shape** = L1 after",
        "scaling the render to the baked energy inside r99; **noise** = the L1 expected from Monte Carlo",
        "noise alone (render + bake); **E/E0** = rendered / baked energy inside r99; **total** = the",
        "rendered total diffuse reflectance (baked albedo, exported Burley A in the header).",
        "Method: validation/check_engine_profiles.py (reciprocal ring illumination; no angular assumption).",
        "",
    ]
    for key, per in rep["results"].items():
        info = rep["engines"].get(key, {})
        lines += [f"## {key}", "", f"{json.dumps(info)}", ""]
        lines.append("| entry | ch | r99 mm | L1 | noise | fit L1 | vs fit | vs-fit noise | shape | E/E0 | total | albedo | A |")
        lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
        for e, r in per.items():
            for ch, c in r["channels"].items():
                lines.append(
                    f"| {e} | {ch} | {c['r99_mm']:.3g} | {c['l1']:.3f} | {c['noise_l1']:.3f} | "
                    f"{c['fit_l1']:.3f} | {c['vs_fit_l1']:.3f} | {c['vs_fit_noise_l1']:.3f} | "
                    f"{c['shape_l1']:.3f} | {c['energy_ratio']:.3f} | {c['total']:.4f} ± {c['total_se']:.4f} | "
                    f"{c['baked_albedo']:.4f} | {c['export_A']:.4f} |"
                )
        lines.append("")
    lines += ["Times (s): " + ", ".join(f"{k} {v:.1f}" for k, v in rep["times_s"].items()), ""]
    lines += [
        "Plot `engine_profiles.png`: a row per entry (" + ", ".join(rep["entries"]) + "), a column per",
        "channel (R, G, B); log r (mm) across, log Rd (mm^-2) up, a grey line per decade (darker: 1 mm,",
        "1 mm^-2), orange: r99; black line: baked; markers: " + ", ".join(
            f"{k} ({s[1]})" for k, s in zip(rep["results"], ENGINE_STYLE)
        ) + ".",
        "",
    ]
    if rep["failures"]:
        lines += ["FAILURES:", ""] + [f"- {f}" for f in rep["failures"]] + [""]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
