#!/usr/bin/env python3
"""Independent check of the skin exports (`baker export profiles.bkt --to TARGET`).

How to run (from anywhere; the repository root is found from this file's path):

    pip install -r validation/requirements.txt
    python3 validation/check_export_skin.py --baker target/release/baker        # bakes a tiny table
    python3 validation/check_export_skin.py --baker target/release/baker --table out/fitzpatrick/profiles.bkt

Without --table the script bakes tests/specs/profiles_small.yaml with --photons 20000 into a
temporary directory (about 10 s) and checks TMP/profiles_small/profiles.bkt. Without --baker
it builds target/release/baker with cargo first. The table is read with validation/bkt.py
(numpy + zstandard), never through the baker.

Burley normalized diffusion (Christensen & Burley 2015, Pixar Tech Memo #15-04):
R(r) = A (e^(-r/d) + e^(-r/3d)) / (8 pi d r), whose energy in the annulus [a, b] is
A (F(b) - F(a)), F(r) = 1 - e^(-r/d)/4 - 3 e^(-r/3d)/4. Fit error (formats/FORMAT.md): the
energy-weighted relative L1 error over the bins with r_edges[k] < r99[c].

Checks (one PASS/FAIL line each, with the worst discrepancy):
  burley   the reported error recomputed in numpy from (A, d) and the table (1e-9 abs);
           gaussian_error_rgb = the table's; (A, d) is a minimum: for d x (1 +- 1 %), with
           the L1-optimal A (weighted median), the error is not lower; summary median/max
  mtlx     MaterialX validates the document against its standard library (open_pbr_surface,
           1.39); one open_pbr_surface per entry; radius x radius_scale = the volume mean
           free path of the Burley JSON, subsurface_color = A/(1 - F0), radius unit = mm
  mitsuba  sigma_t x scale = 1/mfp; the albedo's normal-incidence albedo 1 - H(1) sqrt(1 - a)
           (Chandrasekhar's H in numpy) = A; Mitsuba 3 (scalar_rgb) loads the XML inside a
           tiny scene (a cube holding an entry's medium behind its null boundary, volpathmis,
           uniform white light, orthographic 16x16 px) and renders finite, non-black pixels;
           and per channel, a cube of that channel's (grey) medium seen head-on with volpath
           shows A within 4 standard errors + 1 % (first, middle and last entry)
  unreal   (the JSON side file) every SubsurfaceProfile field present and positive; Unreal's
           own conversion (MFP cm -> DMFP mm -> d = DMFP/(3.5 + 100 (A-0.33)^4)) gives back d
  unreal.py  the editor script parses (ast) and, run twice against a stand-in `unreal` module
           that accepts only the names of validation/engine_reference/unreal_python_api.json,
           creates one SubsurfaceProfile per entry, then updates the same assets (no new
           ones); every field set equals the JSON side file, within Unreal's clamps
  unity    (profiles.json) every HDRP field present and positive; colour x multiplier = d (mm)
  unity.asset  every .asset parses as Unity YAML (ruamel.yaml) with the header, m_Script GUID,
           m_Version and exactly the profile fields of validation/engine_reference/
           hdrp_diffusion_profile.json, values within its ranges and equal to profiles.json
           (single precision); every .meta has a unique 32-hex GUID = profiles.json's
  stderr   every export prints the Burley fit line; its worst error per channel = the max of
           the Burley JSON's fit errors
  blender  the script compiles (Blender is not needed) and, run against a stand-in `bpy`,
           sets Subsurface Radius = 4 pi d, Base Color = A/(1 - F0), method BURLEY
  pbrt     one MakeNamedMaterial "subsurface" per entry; mfp and reflectance as mtlx
  stdout   `-o FILE` and stdout give identical bytes
Finally prints `check_export_skin: N passed, M failed`; exits with 1 if any check fails.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import types
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))  # validation/bkt.py
from bkt import read_bkt  # noqa: E402

TARGETS = {"burley": "json", "mtlx": "mtlx", "blender": "py", "unreal": "unreal.py",
           "unity": "unity", "pbrt": "pbrt", "mitsuba": "xml"}
ENGINE_REF = Path(__file__).resolve().parent / "engine_reference"
TOL_ERR, TOL_REL, TOL_PRINT = 1e-9, 1e-5, 2e-6
SHOW = 6


# ---------------------------------------------------------------------------------------------
# Burley in numpy


def burley_energy(d, lo, hi):
    """F(hi) - F(lo) of the normalized Burley profile, as positive differences."""
    return (0.25 * (np.exp(-lo / d) - np.exp(-hi / d))
            + 0.75 * (np.exp(-lo / (3 * d)) - np.exp(-hi / (3 * d))))


def counted(edges, r99):
    """Bins with r_edges[k] < r99 (bin 0 always; all when r99 is NaN)."""
    nr = len(edges) - 1
    if not np.isfinite(r99):
        return nr
    return max(1, int(np.sum(edges[:-1] < r99)))


def channel(tab, name, c):
    edges = tab[f"{name}/r_edges_mm"]
    rd = tab[f"{name}/rd_rgb_per_mm2"][:, c]
    r99 = tab[f"{name}/r99_mm"][c]
    n = counted(edges, r99)
    lo, hi = edges[:n], edges[1:n + 1]
    return lo, hi, rd[:n] * np.pi * (hi ** 2 - lo ** 2)


def error_of(a, d, lo, hi, t):
    return np.abs(a * burley_energy(d, lo, hi) - t).sum() / t.sum()


def best_a(d, lo, hi, t):
    """The A minimising sum |A E_k - T_k|: weighted median of T/E with weights E."""
    e = burley_energy(d, lo, hi)
    m = e > 0
    x, w = t[m] / e[m], e[m]
    o = np.argsort(x)
    cw = np.cumsum(w[o])
    return max(float(x[o][np.searchsorted(cw, 0.5 * cw[-1])]), 0.0)


def s_perp(a):
    return 1.85 - a + 7 * np.abs(a - 0.8) ** 3


def s_dmfp(a):
    return 3.5 + 100 * (a - 0.33) ** 4


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


# ---------------------------------------------------------------------------------------------
# Checks: each returns (summary, [failure lines])


def check_burley(doc, tab, names):
    bad, worst_err, margin = [], 0.0, math.inf
    if [e["name"] for e in doc["entries"]] != names:
        bad.append("entries differ from the table's (names or order)")
    for e in doc["entries"]:
        name = e["name"]
        g = tab.get(f"{name}/gaussians/error_rgb")
        for c in range(3):
            a, d, err = e["A_rgb"][c], e["d_mm_rgb"][c], e["burley_error_rgb"][c]
            if not (a > 0 and d > 0):
                bad.append(f"{name} ch{c}: A {a} d {d} not positive")
                continue
            lo, hi, t = channel(tab, name, c)
            ours = error_of(a, d, lo, hi, t)
            worst_err = max(worst_err, abs(ours - err))
            if abs(ours - err) > TOL_ERR:
                bad.append(f"{name} ch{c}: error {err} reported, {ours} recomputed")
            for f in (0.99, 1.01):
                other = error_of(best_a(d * f, lo, hi, t), d * f, lo, hi, t)
                margin = min(margin, other - err)
                if other < err - 1e-9:
                    bad.append(f"{name} ch{c}: d x {f} gives error {other} < {err}")
            if g is not None and e["gaussian_error_rgb"][c] != g[c]:
                bad.append(f"{name} ch{c}: gaussian error {e['gaussian_error_rgb'][c]} != table {g[c]}")
            mfp = e["mfp_mm_rgb"]["volume_perpendicular"][c]
            if rel(mfp, d * s_perp(a)) > 1e-12:
                bad.append(f"{name} ch{c}: volume mfp {mfp} != d s(A) {d * s_perp(a)}")
    errs = np.array([e["burley_error_rgb"] for e in doc["entries"]])
    summ = doc["summary"]["burley_error_rgb"]
    if not (np.allclose(summ["median"], np.median(errs, axis=0), rtol=0, atol=1e-12)
            and np.allclose(summ["max"], errs.max(axis=0), rtol=0, atol=1e-12)):
        bad.append(f"summary {summ} != recomputed median {np.median(errs, 0)} max {errs.max(0)}")
    gerr = np.array([e["gaussian_error_rgb"] for e in doc["entries"]], dtype=float)
    fmt = lambda v: " ".join(f"{x:.4f}" for x in v)  # noqa: E731
    print(f"  Burley error   median R G B {fmt(np.median(errs, 0))}   max {fmt(errs.max(0))}")
    print(f"  6-Gaussian     median R G B {fmt(np.nanmedian(gerr, 0))}   max {fmt(np.nanmax(gerr, 0))}")
    return (f"{len(doc['entries'])} entries: error recomputed to {worst_err:.1e}, "
            f"no better d at +-1 % (smallest gain {margin:.1e})"), bad


def entry_fits(doc):
    """name -> (A, d, volume mfp, f0) from the Burley JSON."""
    return {e["name"]: (np.array(e["A_rgb"]), np.array(e["d_mm_rgb"]),
                        np.array(e["mfp_mm_rgb"]["volume_perpendicular"]), e["f0"])
            for e in doc["entries"]}


def check_mtlx(path, fits):
    from mtlx_doc import load_validated

    doc, ok, msg = load_validated(path)
    bad = [] if ok else [f"MaterialX: {msg.strip()[:400]}"]
    shaders = [n for n in doc.getNodes() if n.getCategory() == "open_pbr_surface"]
    materials = [n for n in doc.getNodes() if n.getCategory() == "surfacematerial"]
    if len(shaders) != len(fits) or len(materials) != len(fits):
        bad.append(f"{len(shaders)} shaders, {len(materials)} materials for {len(fits)} entries")
    worst = 0.0
    by_doc = {}
    for m in materials:
        name = m.getAttribute("doc").removeprefix("skin entry ")
        sh = m.getInput("surfaceshader").getNodeName()
        by_doc[name] = doc.getNode(sh)
    for name, (a, d, mfp, f0) in fits.items():
        n = by_doc.get(name)
        if n is None:
            bad.append(f"{name}: no material")
            continue
        if n.getNodeDef() is None or n.getNodeDef().getName() != "ND_open_pbr_surface_surfaceshader":
            bad.append(f"{name}: node definition not found")
        radius_in = n.getInput("subsurface_radius")
        radius = radius_in.getValue()
        scale = np.array(list(n.getInputValue("subsurface_radius_scale")))
        color = np.array(list(n.getInputValue("subsurface_color")))
        if radius_in.getUnit() != "millimeter":
            bad.append(f"{name}: subsurface_radius unit {radius_in.getUnit()!r}")
        if n.getInputValue("subsurface_weight") != 1.0:
            bad.append(f"{name}: subsurface_weight != 1")
        want_c = np.clip(a / (1 - f0), 0, 1)
        dev = max(np.max(np.abs(radius * scale / mfp - 1)), np.max(np.abs(color - want_c)))
        worst = max(worst, dev)
        if dev > TOL_REL:
            bad.append(f"{name}: radius x scale {radius * scale} vs mfp {mfp}; colour {color} vs {want_c}")
        if np.any(scale > 1 + 1e-9) or np.any(scale < 0):
            bad.append(f"{name}: subsurface_radius_scale {scale} outside [0, 1]")
    return f"valid ({len(shaders)} open_pbr_surface), values to {worst:.1e}", bad


# The exported XML, included as is: a cube holding one entry's medium behind its null boundary.
MITSUBA_SCENE = """<scene version="3.0.0">
    <include filename="{export}"/>
    <integrator type="volpathmis"><integer name="max_depth" value="-1"/></integrator>
    <sensor type="orthographic">
        <transform name="to_world"><lookat origin="0, 0, {dist}" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="cube">
        <transform name="to_world"><scale value="{half}"/></transform>
        <ref id="{id}_boundary"/>
        <ref name="interior" id="{id}"/>
    </shape>
</scene>
"""

# One channel of a medium in units of its mean free path (sigma_t = 1), a cube 60 mean free
# paths wide: coordinates stay small, so Mitsuba's single-precision ray offsets (which grow
# with the coordinates) stay far below the mean free path. A grey medium, so plain volpath,
# which matched Chandrasekhar's albedo within 2 standard errors at 0.5, 0.86 and 0.95 (64k
# paths); volpathmis with its default Russian roulette read about 1 % low.
MITSUBA_CHANNEL = """<scene version="3.0.0">
    <bsdf type="null" id="boundary"/>
    <medium type="homogeneous" id="medium">
        <float name="albedo" value="{albedo}"/>
        <float name="sigma_t" value="1"/>
        <phase type="isotropic"/>
    </medium>
    <integrator type="volpath"><integer name="max_depth" value="-1"/></integrator>
    <sensor type="orthographic">
        <transform name="to_world"><lookat origin="0, 0, 90" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="cube">
        <transform name="to_world"><scale value="30"/></transform>
        <ref id="boundary"/>
        <ref name="interior" id="medium"/>
    </shape>
</scene>
"""


def normal_incidence_albedo(alpha):
    """1 - H(1) sqrt(1 - alpha) for an index-matched isotropic half-space, H from
    Chandrasekhar's explicit integral ln H(1) = -(1/pi) int_0^(pi/2) ln(1 - alpha t cot t) dt."""
    x, w = np.polynomial.legendre.leggauss(96)
    t, w = (x + 1) * np.pi / 4, w * np.pi / 4
    alpha = np.atleast_1d(alpha)[:, None]
    h1 = np.exp(-np.sum(w * np.log(1 - alpha * t / np.tan(t)), axis=1) / np.pi)
    return 1 - h1 * np.sqrt(1 - alpha[:, 0])


def check_mitsuba(path, fits, workdir, spp=64):
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    bad = []
    root = ET.parse(path).getroot()
    media = {m.get("id"): m for m in root.iter("medium")}
    bsdfs = {b.get("id") for b in root.iter("bsdf")}
    if len(media) != len(fits):
        bad.append(f"{len(media)} media for {len(fits)} entries")
    ids = [m.get("id") for m in root.iter("medium")]  # document order = table order
    worst_sig, worst_alb = 0.0, 0.0
    for mid, (name, (a, d, mfp, f0)) in zip(ids, fits.items()):
        m = media[mid]
        if f"{mid}_boundary" not in bsdfs:
            bad.append(f"{mid}: no boundary bsdf")
        vals = {e.get("name"): e.get("value") for e in m if e.get("name")}
        sig = np.array([float(x) for x in vals["sigma_t"].split(",")]) * float(vals["scale"])
        alb = np.array([float(x) for x in vals["albedo"].split(",")])
        worst_sig = max(worst_sig, np.max(np.abs(sig * mfp - 1)))
        worst_alb = max(worst_alb, np.max(np.abs(normal_incidence_albedo(alb) - a)))
        if np.max(np.abs(sig * mfp - 1)) > TOL_REL:
            bad.append(f"{mid} ({name}): sigma_t x scale {sig} != 1/mfp {1 / mfp}")
        if np.any(alb < 0) or np.any(alb > 1) or np.max(np.abs(normal_incidence_albedo(alb) - a)) > TOL_REL:
            bad.append(f"{mid}: albedo {alb}: normal-incidence albedo {normal_incidence_albedo(alb)} != A {a}")
    # (1) The export as written: three entries (first, middle, last), each a cube 60 of its
    # largest mean free paths wide, rendered 16x16: finite pixels, not black.
    picks = sorted({0, len(ids) // 2, len(ids) - 1})
    for i in picks:
        half = 30 * float(np.max(list(fits.values())[i][2]))
        scene = Path(workdir) / f"mitsuba_scene_{i}.xml"
        scene.write_text(MITSUBA_SCENE.format(export=Path(path).resolve(), id=ids[i], half=half,
                                              dist=3 * half, spp=16))
        img = np.array(mi.render(mi.load_file(str(scene)), seed=1))[:, :, :3]
        if not np.all(np.isfinite(img)):
            bad.append(f"{ids[i]}: non-finite pixels")
        elif not np.all(img.mean(axis=(0, 1)) > 0):
            bad.append(f"{ids[i]}: black render {img.mean(axis=(0, 1))}")
    # (2) Physics: each channel's medium, seen head-on under uniform white light, shows the
    # fitted albedo A (the table's normal-incidence reflectance), within 4 standard errors + 1 %.
    worst_render = 0.0
    for i in picks:
        a = list(fits.values())[i][0]
        m = media[ids[i]]
        alb = [float(x) for x in m.find("rgb[@name='albedo']").get("value").split(",")]
        for c in range(3):
            scene = Path(workdir) / f"mitsuba_channel_{i}_{c}.xml"
            scene.write_text(MITSUBA_CHANNEL.format(albedo=alb[c], spp=spp))
            img = np.array(mi.render(mi.load_file(str(scene)), seed=1))[:, :, 0]
            mean, se = float(img.mean()), float(img.std() / math.sqrt(img.size))
            worst_render = max(worst_render, abs(mean / a[c] - 1))
            if not abs(mean - a[c]) <= 4 * se + 0.01 * a[c]:
                bad.append(f"{ids[i]} ch{c}: rendered albedo {mean:.4f} +- {se:.4f}, A {a[c]:.4f}")
    return (f"loads and renders {len(picks)} entries; sigma_t to {worst_sig:.1e}, albedo to "
            f"{worst_alb:.1e}; rendered normal-incidence albedo = A to {worst_render:.1%}"), bad


def check_unreal(doc, fits):
    bad, worst = [], 0.0
    profiles = {p["name"]: p for p in doc["profiles"]}
    for name, (a, d, mfp, f0) in fits.items():
        p = profiles.get(name, {}).get("SubsurfaceProfile")
        if p is None:
            bad.append(f"{name}: missing")
            continue
        for k in ("SurfaceAlbedo", "MeanFreePathColor", "MeanFreePathDistance", "WorldUnitScale"):
            if k not in p:
                bad.append(f"{name}: no {k}")
        sa = np.array([p["SurfaceAlbedo"][k] for k in "RGB"])
        col = np.array([p["MeanFreePathColor"][k] for k in "RGB"])
        dist = p["MeanFreePathDistance"]
        if not (dist >= 0.1 and p["WorldUnitScale"] > 0 and np.all(sa > 0) and np.all(col > 0)
                and np.all(col <= 1 + 1e-12) and np.all(sa <= 1)):
            bad.append(f"{name}: not positive / out of range: {p}")
        # Unreal's chain (SubsurfaceProfile.cpp, BurleyNormalizedSSS.cpp), re-implemented.
        dmfp_mm = col * dist * s_dmfp(sa) / s_perp(sa) * 10 / 0.6
        d_unreal = dmfp_mm / s_dmfp(sa)
        dev = np.max(np.abs(d_unreal / d - 1))
        worst = max(worst, dev)
        if dev > 1e-9:
            bad.append(f"{name}: Unreal renders d {d_unreal}, fit d {d}")
    return f"{len(profiles)} profiles, Unreal's d = fitted d to {worst:.1e}", bad


def check_unity(doc, fits):
    bad, worst = [], 0.0
    profiles = {p["name"]: p for p in doc["profiles"]}
    for name, (a, d, mfp, f0) in fits.items():
        p = profiles.get(name, {}).get("DiffusionProfile")
        if p is None:
            bad.append(f"{name}: missing")
            continue
        need = ("scatteringDistance", "scatteringDistanceMultiplier", "transmissionTint",
                "worldScale", "ior", "thicknessRemap", "texturingMode", "transmissionMode")
        missing = [k for k in need if k not in p]
        if missing:
            bad.append(f"{name}: no {missing}")
            continue
        sd = np.array([p["scatteringDistance"][k] for k in "rgb"])
        m = p["scatteringDistanceMultiplier"]
        if not (m > 0 and p["worldScale"] > 0 and p["ior"] >= 1 and np.all(sd > 0) and np.all(sd <= 1)):
            bad.append(f"{name}: not positive / out of range: {p}")
        dev = np.max(np.abs(sd * m / d - 1))
        worst = max(worst, dev)
        if dev > 1e-12:
            bad.append(f"{name}: scatteringDistance x multiplier {sd * m} != d {d}")
    return f"{len(profiles)} profiles, colour x multiplier = d to {worst:.1e}", bad


class _Socket:
    def __init__(self, name=""):
        self.name = name
        self.default_value = None
        self.is_linked = False


class _Sockets(dict):
    """node.inputs: by name (`inputs["IOR"]`, `"IOR" in inputs`); iterates over the sockets,
    as bpy's collections do."""

    def __iter__(self):
        return iter(list(self.values()))


class _Node:
    def __init__(self, type_):
        self.type = type_
        self.subsurface_method = "RANDOM_WALK"
        names = ["Base Color", "Subsurface Weight", "Subsurface Radius", "Subsurface Scale", "IOR",
                 "Subsurface IOR", "Subsurface Anisotropy", "Surface"]
        self.inputs = _Sockets({n: _Socket(n) for n in names})
        self.outputs = _Sockets({"BSDF": _Socket("BSDF")})


class _Nodes(list):
    def new(self, kind):
        n = _Node({"ShaderNodeBsdfPrincipled": "BSDF_PRINCIPLED",
                   "ShaderNodeOutputMaterial": "OUTPUT_MATERIAL"}[kind])
        self.append(n)
        return n


class _Links:
    def new(self, _out, inp):
        inp.is_linked = True


class _Material:
    def __init__(self, name):
        self.name, self.use_nodes = name, False
        self.node_tree = types.SimpleNamespace(nodes=_Nodes(), links=_Links())


class _Materials(dict):
    def new(self, name):
        self[name] = _Material(name)
        return self[name]


def check_blender(path, fits):
    src = Path(path).read_text()
    compile(src, str(path), "exec")
    bpy = types.ModuleType("bpy")
    bpy.data = types.SimpleNamespace(materials=_Materials())
    bpy.app = types.SimpleNamespace(version=(5, 0, 1))  # the version CI's bpy venv holds
    bpy.context = types.SimpleNamespace(
        scene=types.SimpleNamespace(unit_settings=types.SimpleNamespace(scale_length=1.0)))
    saved = sys.modules.get("bpy")
    sys.modules["bpy"] = bpy
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            exec(compile(src, str(path), "exec"), {"__name__": "__main__"})
    finally:
        if saved is None:
            del sys.modules["bpy"]
        else:
            sys.modules["bpy"] = saved
    bad, worst = [], 0.0
    mats = bpy.data.materials
    for name, (a, d, mfp, f0) in fits.items():
        m = mats.get(name)
        if m is None:
            bad.append(f"{name}: no material")
            continue
        n = next(x for x in m.node_tree.nodes if x.type == "BSDF_PRINCIPLED")
        radius = np.array(n.inputs["Subsurface Radius"].default_value)
        scale = n.inputs["Subsurface Scale"].default_value
        base = np.array(n.inputs["Base Color"].default_value[:3])
        want = np.clip(a / (1 - f0), 0, 1)
        # Cycles: d = radius x scale / (4 pi), scale in metres per mm at scale_length 1.
        dev = max(np.max(np.abs(radius * scale / (4 * math.pi) / (d * 1e-3) - 1)),
                  np.max(np.abs(base - want)))
        worst = max(worst, dev)
        if dev > TOL_REL or n.subsurface_method != "BURLEY" or n.inputs["Subsurface Weight"].default_value != 1:
            bad.append(f"{name}: radius {radius} scale {scale} base {base} method {n.subsurface_method}")
    return f"compiles; {len(mats)} materials set through a stand-in bpy, values to {worst:.1e}", bad


def check_pbrt(path, fits):
    text = Path(path).read_text()
    blocks = re.findall(r'MakeNamedMaterial "((?:[^"\\]|\\.)*)"(.*?)(?=\n\s*\n|\Z)', text, re.S)
    bad, worst = [], 0.0
    if len(blocks) != len(fits):
        bad.append(f"{len(blocks)} materials for {len(fits)} entries")
    for name, body in blocks:
        params = dict(re.findall(r'"(\w+ \w+)" \[ ([^\]]*) \]', body))
        if params.get("string type") != '"subsurface"':
            bad.append(f"{name}: type {params.get('string type')}")
            continue
        a, d, mfp, f0 = fits[name]
        got_mfp = np.array(params["rgb mfp"].split(), dtype=float)
        got_r = np.array(params["rgb reflectance"].split(), dtype=float)
        dev = max(np.max(np.abs(got_mfp / mfp - 1)), np.max(np.abs(got_r - np.clip(a / (1 - f0), 0, 1))))
        worst = max(worst, dev)
        if dev > TOL_REL or float(params["float scale"]) <= 0 or float(params["float eta"]) < 1:
            bad.append(f"{name}: {params}")
    return f"{len(blocks)} subsurface materials, values to {worst:.1e}", bad


# ---------------------------------------------------------------------------------------------
# Engines that cannot run here: Unreal's script against a stand-in API, Unity's YAML against
# HDRP's serialisation (validation/engine_reference/).


def fake_unreal(api, store, log):
    """A stand-in `unreal` module: the names of unreal_python_api.json and nothing else.
    `store` maps asset paths to SubsurfaceProfile objects (the 'content browser')."""
    struct_props = api["SubsurfaceProfileStruct"]["editor_properties"]
    types_ = {"float": (float, int), "bool": (bool,), "LinearColor": (None,)}

    class LinearColor:
        def __init__(self, r, g, b, a):
            self.rgba = (float(r), float(g), float(b), float(a))

    types_["LinearColor"] = (LinearColor,)

    class Props:
        allowed: dict = {}

        def __init__(self):
            self.values = {}

        def get_editor_property(self, name):
            if name not in self.allowed:
                raise AttributeError(f"{type(self).__name__} has no editor property {name!r}")
            return self.values.get(name)

        def set_editor_property(self, name, value):
            if name not in self.allowed:
                raise AttributeError(f"{type(self).__name__} has no editor property {name!r}")
            want = self.allowed[name]
            ok = isinstance(value, types_[want]) if want in types_ else isinstance(value, globals_[want])
            if want == "float" and isinstance(value, bool):
                ok = False
            if not ok:
                raise TypeError(f"{name}: {want} expected, got {type(value).__name__}")
            self.values[name] = value

    class SubsurfaceProfileStruct(Props):
        allowed = struct_props

    class SubsurfaceProfile(Props):
        allowed = api["SubsurfaceProfile"]["editor_properties"]

        def __init__(self, path):
            super().__init__()
            self.path = path
            self.values["settings"] = SubsurfaceProfileStruct()

        def get_editor_property(self, name):
            v = super().get_editor_property(name)
            copy = SubsurfaceProfileStruct()  # Unreal returns a copy of a struct property
            copy.values = dict(v.values)
            return copy

        def get_path_name(self):
            return self.path

    globals_ = {"SubsurfaceProfileStruct": SubsurfaceProfileStruct}

    class SubsurfaceProfileFactory:
        pass

    class AssetTools:
        def create_asset(self, asset_name, package_path, asset_class, factory):
            if asset_class is not SubsurfaceProfile or not isinstance(factory, SubsurfaceProfileFactory):
                raise TypeError("create_asset: SubsurfaceProfile with its factory expected")
            path = package_path + "/" + asset_name
            if path in store:
                raise RuntimeError(f"{path} exists")
            store[path] = SubsurfaceProfile(path)
            log.append(("create", path))
            return store[path]

    class AssetToolsHelpers:
        @staticmethod
        def get_asset_tools():
            return AssetTools()

    class EditorAssetLibrary:
        @staticmethod
        def does_asset_exist(asset_path):
            return asset_path in store

        @staticmethod
        def load_asset(asset_path):
            log.append(("load", asset_path))
            return store.get(asset_path)

        @staticmethod
        def save_loaded_asset(asset_to_save, only_if_is_dirty=True):
            log.append(("save", asset_to_save.path))
            return True

    m = types.ModuleType("unreal")
    for obj in (LinearColor, SubsurfaceProfileStruct, SubsurfaceProfile, SubsurfaceProfileFactory,
                AssetToolsHelpers, EditorAssetLibrary):
        setattr(m, obj.__name__, obj)
    m.log = lambda arg: log.append(("log", arg))
    return m


def check_unreal_script(script, doc):
    import ast
    api = json.loads((ENGINE_REF / "unreal_python_api.json").read_text())
    clamps = api["SubsurfaceProfileStruct"]["clamps_SubsurfaceProfile_h_UE54"]
    src = script.read_text()
    ast.parse(src)
    bad, store, log = [], {}, []
    code = compile(src, str(script), "exec")
    saved = sys.modules.get("unreal")
    try:
        sys.modules["unreal"] = fake_unreal(api, store, log)
        for _ in range(2):  # the second run must update the assets of the first
            exec(code, {"__name__": "__main__"})
    finally:
        if saved is None:
            sys.modules.pop("unreal", None)
        else:
            sys.modules["unreal"] = saved
    n = len(doc["profiles"])
    creates = [x for x in log if x[0] == "create"]
    loads = [x for x in log if x[0] == "load"]
    saves = [x for x in log if x[0] == "save"]
    if len(creates) != n or len(loads) != n or len(saves) != 2 * n or len(store) != n:
        bad.append(f"{n} profiles: {len(creates)} created, {len(loads)} reloaded, {len(saves)} saves")
    worst = 0.0
    for p in doc["profiles"]:
        path = "/Game/BakerSkin/" + p["asset"]
        a = store.get(path)
        if a is None:
            bad.append(f"{p['name']}: no asset {path}")
            continue
        got = a.values["settings"].values
        sp = p["SubsurfaceProfile"]
        want = {"surface_albedo": [sp["SurfaceAlbedo"][k] for k in "RGB"],
                "mean_free_path_color": [sp["MeanFreePathColor"][k] for k in "RGB"],
                "mean_free_path_distance": sp["MeanFreePathDistance"],
                "world_unit_scale": sp["WorldUnitScale"], "ior": sp["IOR"],
                "enable_burley": True, "enable_mean_free_path": True}
        for k, w in want.items():
            g = got.get(k)
            if g is None:
                bad.append(f"{p['name']}: {k} not set")
                continue
            g = list(g.rgba[:3]) if hasattr(g, "rgba") else g
            if isinstance(w, bool):
                if g is not w:
                    bad.append(f"{p['name']}: {k} = {g}")
                continue
            dev = float(np.max(np.abs(np.asarray(g, float) - np.asarray(w, float))))
            worst = max(worst, dev)
            if dev != 0.0:
                bad.append(f"{p['name']}: {k} = {g}, JSON {w}")
            lo, hi = clamps.get(k, (-np.inf, np.inf))
            if k == "surface_albedo":
                lo = 0.0  # below 0.01 Unreal clamps (noted in the JSON), not an error
            if np.any(np.asarray(g, float) < lo) or np.any(np.asarray(g, float) > hi):
                bad.append(f"{p['name']}: {k} = {g} outside Unreal's clamp [{lo}, {hi}]")
    return (f"{n} assets created, rerun updated them in place; fields = JSON to {worst:.0e}, "
            f"names of the UE Python API"), bad


def check_unity_assets(folder, doc):
    from ruamel.yaml import YAML
    ref = json.loads((ENGINE_REF / "hdrp_diffusion_profile.json").read_text())
    yaml = YAML(typ="safe", pure=True)
    header = "%YAML 1.1\n%TAG !u! tag:unity3d.com,2011:\n--- !u!114 &11400000\n"
    bad, guids, worst = [], set(), 0.0
    listed = set(doc["files"])
    present = {p.name for p in folder.iterdir()}
    if present != listed:
        bad.append(f"folder holds {sorted(present ^ listed)[:4]} not matching profiles.json")
    rng = ref["ranges"]
    for p in doc["profiles"]:
        text = (folder / p["asset"]).read_text()
        if not text.startswith(header):
            bad.append(f"{p['asset']}: header {text[:60]!r}")
            continue
        mb = yaml.load(text[len(header):])["MonoBehaviour"]
        if mb["m_Script"] != ref["m_Script"] or mb["m_Version"] != ref["m_Version"]:
            bad.append(f"{p['asset']}: m_Script {mb['m_Script']}, m_Version {mb['m_Version']}")
        if mb["m_Name"] != p["name"]:
            bad.append(f"{p['asset']}: m_Name {mb['m_Name']!r}")
        prof = mb["profile"]
        if list(prof) != ref["profile_fields"]:
            bad.append(f"{p['asset']}: fields {list(prof)}")
            continue
        dp = p["DiffusionProfile"]
        sd = [prof["scatteringDistance"][k] for k in "rgb"]
        want = [dp["scatteringDistance"][k] for k in "rgb"]
        f32 = lambda x: float(np.float32(x))  # noqa: E731
        dev = max(abs(f32(a) - f32(b)) for a, b in zip(sd + [prof["scatteringDistanceMultiplier"], prof["ior"]],
                                                   want + [dp["scatteringDistanceMultiplier"], dp["ior"]]))
        worst = max(worst, dev)
        if dev > 0:
            bad.append(f"{p['asset']}: values differ from profiles.json by {dev:.1e}")
        ok = (all(0 <= x <= 1 for x in sd) and prof["scatteringDistanceMultiplier"] > 0
              and rng["ior"][0] <= prof["ior"] <= rng["ior"][1]
              and prof["worldScale"] >= rng["worldScale"][0]
              and rng["lobeMix"][0] <= prof["lobeMix"] <= rng["lobeMix"][1]
              and rng["diffuseShadingPower"][0] <= prof["diffuseShadingPower"] <= rng["diffuseShadingPower"][1]
              and all(rng["smoothnessMultipliers"][0] <= v <= rng["smoothnessMultipliers"][1]
                      for v in prof["smoothnessMultipliers"].values())
              and prof["texturingMode"] in rng["texturingMode"].values()
              and prof["transmissionMode"] in rng["transmissionMode"].values()
              and 0 <= prof["thicknessRemap"]["x"] <= prof["thicknessRemap"]["y"])
        if not ok:
            bad.append(f"{p['asset']}: outside HDRP's ranges: {prof}")
        meta = yaml.load((folder / (p["asset"] + ".meta")).read_text())
        g = str(meta["guid"])
        if not (re.fullmatch(r"[0-9a-f]{32}", g) and g == p["guid"] and g not in guids
                and meta["NativeFormatImporter"]["mainObjectFileID"] == ref["meta"]["mainObjectFileID"]):
            bad.append(f"{p['asset']}.meta: guid {g!r}, {meta}")
        guids.add(g)
    return (f"{len(doc['profiles'])} .asset + .meta parse as HDRP serialises them; values = "
            f"profiles.json to {worst:.0e}; {len(guids)} distinct GUIDs"), bad


def check_stderr(stderr, burley):
    errs = np.array([e["burley_error_rgb"] for e in burley["entries"]], float)
    worst = errs.max(axis=0)
    bad = []
    for t, text in stderr.items():
        m = re.search(r"Burley fit of (\d+) entr.*R ([0-9.]+) .*G ([0-9.]+) .*B ([0-9.]+) ", text)
        if not m:
            bad.append(f"--to {t}: no fit line on stderr: {text[:200]!r}")
            continue
        got = np.array([float(m.group(i)) for i in (2, 3, 4)])
        if int(m.group(1)) != len(errs) or np.any(np.abs(got - worst) > 5e-5):
            bad.append(f"--to {t}: {m.group(0)!r}, worst {worst}")
    return f"{len(stderr)} targets print the fit line (worst R G B {np.round(worst, 4)})", bad


def rerun_unity(baker, table, folder):
    """A re-export replaces the folder in place (same GUIDs); a stranger in it stops it."""
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    cmd = [str(baker), "export", str(table), "--to", "unity", "-o", str(folder), "-q"]
    subprocess.run(cmd, check=True, timeout=600)
    after = {p.name: p.read_bytes() for p in folder.iterdir()}
    bad = [] if after == before else ["a re-export changed the folder"]
    (folder / "notes.txt").write_text("mine")
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if p.returncode == 0 or "notes.txt" not in p.stderr or not (folder / "notes.txt").exists():
        bad.append(f"a folder with a file of the user's was replaced: {p.returncode} {p.stderr[-300:]}")
    (folder / "notes.txt").unlink()
    return "re-export identical; a user's file in the folder stops it", bad


# ---------------------------------------------------------------------------------------------


def build_baker() -> Path:
    print("building: cargo build --release -q -p baker", flush=True)
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "baker"], cwd=REPO, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return (target if target.is_absolute() else REPO / target) / "release" / "baker"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baker", help="baker binary (default: cargo build --release, target/release/baker)")
    ap.add_argument("--table", help="profiles.bkt to export (default: bake tests/specs/profiles_small.yaml)")
    ap.add_argument("--photons", type=int, default=20000, help="photons for the default bake (20000)")
    ap.add_argument("--keep", metavar="DIR", help="write the bake and the exports to DIR and keep them")
    args = ap.parse_args()
    baker = Path(args.baker).resolve() if args.baker else build_baker()

    tmp = None
    if args.keep:
        work = Path(args.keep).resolve()
        work.mkdir(parents=True, exist_ok=True)
    else:
        tmp = tempfile.TemporaryDirectory(prefix="check_export_skin_")
        work = Path(tmp.name)
    try:
        if args.table:
            table = Path(args.table).resolve()
        else:
            spec = REPO / "tests/specs/profiles_small.yaml"
            cmd = [str(baker), "bake", str(spec), "--out", str(work), "--quiet",
                   "--photons", str(args.photons)]
            print("running:", " ".join(cmd), flush=True)
            subprocess.run(cmd, check=True, timeout=3600)
            table = work / spec.stem / "profiles.bkt"
        print(f"checking exports of {table}")
        kind, meta, tab = read_bkt(str(table))
        names = json.loads(meta["entries"])

        files, stderr = {}, {}
        for t, ext in TARGETS.items():
            out = work / f"skin.{ext}"
            cmd = [str(baker), "export", str(table), "--to", t, "-o", str(out)]
            if t == "blender":  # the Christensen-Burley method this check recomputes
                cmd += ["--method", "burley"]
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
            if p.returncode != 0:
                print(f"FAIL export --to {t}: exit {p.returncode}: {p.stderr.strip()[-2000:]}")
                return 1
            files[t], stderr[t] = out, p.stderr

        results = []

        def run(label, fn, *a):
            try:
                summary, bad = fn(*a)
            except Exception as ex:  # a crash in a check is a failure of that check
                summary, bad = "", [f"{type(ex).__name__}: {ex}"]
            ok = not bad
            results.append(ok)
            print(f"{'PASS' if ok else 'FAIL'} {label:8s} {summary}")
            for line in bad[:SHOW]:
                print(f"       {line}")
            if len(bad) > SHOW:
                print(f"       … and {len(bad) - SHOW} more")

        burley = json.loads(files["burley"].read_text())
        fits = entry_fits(burley)
        run("burley", check_burley, burley, tab, names)
        run("mtlx", check_mtlx, files["mtlx"], fits)
        run("mitsuba", check_mitsuba, files["mitsuba"], fits, work)
        unreal_json = json.loads(files["unreal"].with_suffix(".json").read_text())
        unity_json = json.loads((files["unity"] / "profiles.json").read_text())
        run("unreal", check_unreal, unreal_json, fits)
        run("unreal.py", check_unreal_script, files["unreal"], unreal_json)
        run("unity", check_unity, unity_json, fits)
        run("unity.asset", check_unity_assets, files["unity"], unity_json)
        run("stderr", check_stderr, stderr, burley)
        run("blender", check_blender, files["blender"], fits)
        run("pbrt", check_pbrt, files["pbrt"], fits)

        def same_on_stdout():
            p = subprocess.run([str(baker), "export", str(table), "--to", "mtlx"],
                               capture_output=True, timeout=600, check=True)
            same = p.stdout == files["mtlx"].read_bytes()
            return "mtlx on stdout = -o file", [] if same else ["stdout differs from -o FILE"]

        run("stdout", same_on_stdout)
        run("unity.rerun", rerun_unity, baker, table, files["unity"])
        passed = sum(results)
        print(f"check_export_skin: {passed} passed, {len(results) - passed} failed")
        return 0 if all(results) else 1
    finally:
        if tmp is not None:
            tmp.cleanup()


if __name__ == "__main__":
    sys.exit(main())
