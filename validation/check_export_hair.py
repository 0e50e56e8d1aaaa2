#!/usr/bin/env python3
"""Fiber export against Mitsuba 3's own `hair` plugin.

How to run (from the repository root; nothing is built here):

    python3 validation/check_export_hair.py --baker target/release/baker

What it does:
  1. bakes two tiny fiber tables (a dyed round polyester fiber and a wool fiber with cuticle
     scales, 10 deg bins, 4096 photons per stored direction: a few seconds) with `baker bake`;
     every step below runs for both;
  2. exports it with `baker export TABLE --to chiang|mitsuba|pbrt|blender -o FILE`, and checks
     that an unknown target or variant is a usage error (exit code 2);
  3. loads the Mitsuba XML with the `mitsuba` package (variant scalar_rgb) inside a scene that
     `<include>`s it, and checks that the plugin holds the parameters of the chiang JSON
     (`targets.mitsuba`);
  4. evaluates that BSDF (`bsdf.eval`) at the JSON's test directions, whose values come from
     the Rust model (baker/src/export/chiang/):
       - `near`: si.wi = wi_local, wo = wo_local in Mitsuba's local frame (tangent y,
         normal z; h = sin gamma(wi));
       - `far`: the average over the fiber width, (1/2) int S dh, by the same composite
         Gauss-Legendre rule in gamma = asin h that the JSON names (`panels` x 8 nodes),
         wi = (-h cos ti, sin ti, sqrt(1 - h^2) cos ti), wo at theta_o and azimuth
         atan2(wi.z, wi.x) + dphi;
     and requires agreement within 1 % relative wherever the value is not tiny (above 1e-3 of
     the largest test value): the check that the exported parameters mean in Mitsuba what
     they mean in our fitted model;
  5. requires a cuticle tilt |alpha| > 1 deg for the wool (so the tilt's unit and sign are
     exercised by step 4);
  6. renders a 16 x 16 image of a hair-BSDF `bsplinecurve` under a constant emitter (the
     XML works in a scene);
  7. checks that the pbrt-v4 snippet and the Blender script carry the same parameters (pbrt:
     the same numbers; Blender: Offset = -alpha in radians, see baker/src/export/fiber/blender.rs).

Exits 1 on any failure. Prints the largest relative differences.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

SPEC = """version: 1
bake: {resolution_deg: 10, photons_per_direction: 4096, seed: 3}
fibers:
  - {name: poly, type: polyester, section: {shape: circle}, dye: disperse_red_1,
     depth_of_shade_percent: 1.0}
  - {name: wool, type: wool, section: {shape: wool}, diameter_um: 30,
     cuticle: {length_um: 10, tilt_deg: 3}, dye: reactive_blue_19, depth_of_shade_percent: 0.5}
"""
# Wool's cuticle scales give a fitted tilt: the check then covers scale_tilt's unit and sign.
TABLES = ["poly", "wool"]

TOLERANCE = 0.01  # relative
TINY = 1e-3  # of the largest test value


def run(cmd, expect=0):
    p = subprocess.run([str(c) for c in cmd], capture_output=True, text=True)
    if p.returncode != expect:
        sys.exit(f"FAIL: {' '.join(map(str, cmd))} exited {p.returncode} (expected {expect})\n"
                 f"{p.stdout}\n{p.stderr}")
    return p


def gauss_legendre_gamma(panels):
    """Nodes gamma and weights of (1/2) int dh over [-1, 1], h = sin gamma (as chiang.rs)."""
    x, w = np.polynomial.legendre.leggauss(8)
    width = math.pi / panels
    mids = -math.pi / 2 + (np.arange(panels) + 0.5) * width
    g = (mids[:, None] + 0.5 * width * x[None, :]).ravel()
    wt = (0.5 * width * w[None, :] * np.ones((panels, 1))).ravel()
    return g, 0.5 * wt * np.cos(g)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baker", default="target/release/baker", help="baker binary")
    ap.add_argument("--keep", help="keep the files in this folder")
    a = ap.parse_args()
    baker = Path(a.baker).resolve()

    import mitsuba as mi
    mi.set_variant("scalar_rgb")

    tmp_ctx = tempfile.TemporaryDirectory()
    tmp = Path(a.keep) if a.keep else Path(tmp_ctx.name)
    tmp.mkdir(parents=True, exist_ok=True)
    spec = tmp / "tiny.yaml"
    spec.write_text(SPEC)
    run([baker, "bake", "--quiet", "--out", tmp / "out", spec])
    failures = []
    for name in TABLES:
        table = tmp / "out" / "tiny" / name / "section-00.bcsdf"
        assert table.exists(), table
        print(f"== {name}")
        failures += [f"{name}: {f}" for f in check_table(mi, baker, table, tmp / name, name)]
    if failures:
        print("FAIL:\n  " + "\n  ".join(failures))
        sys.exit(1)
    print("OK")


def check_table(mi, baker, table, tmp, name):
    """Exports `table` to every target in `tmp` and returns the failures."""
    tmp.mkdir(parents=True, exist_ok=True)
    files = {}
    for target, ext in [("chiang", "json"), ("mitsuba", "xml"), ("pbrt", "pbrt"),
                        ("blender", "py")]:
        files[target] = tmp / f"{name}_hair.{ext}"
        p = run([baker, "export", table, "--to", target, "-o", files[target]])
        print(f"export --to {target}: {p.stderr.strip()}")
    run([baker, "export", table, "--to", "nonsense"], expect=2)
    run([baker, "export", table, "--to", "pbrt", "--entry", "no_such_variant"], expect=2)

    doc = json.loads(files["chiang"].read_text())
    par, fit = doc["parameters"], doc["fit"]
    failures = []
    if name == "wool" and abs(par["alpha_deg"]) < 1.0:
        failures.append(f"wool: fitted tilt {par['alpha_deg']} deg, expected |alpha| > 1 deg")
    if not (0.0 <= fit["rel_l1"] < 2.0 and math.isfinite(fit["rel_l2"])):
        failures.append(f"fit error out of range: {fit['rel_l1']}, {fit['rel_l2']}")
    if not (0.0 <= par["beta_m"] <= 1.0 and 0.0 <= par["beta_n"] <= 1.0):
        failures.append(f"roughness out of [0, 1]: {par}")
    print(f"fit: relative L1 {fit['rel_l1']:.4f}, L2 {fit['rel_l2']:.4f}, noise L1 estimate "
          f"{fit['noise_l1_estimate']}, eta {par['eta']:.4f}, beta_m {par['beta_m']:.4f}, "
          f"beta_n {par['beta_n']:.4f}, alpha {par['alpha_deg']:.3f} deg, sigma_a {par['sigma_a']}")

    # --- Mitsuba: the exported XML inside a scene with a curve that uses it.
    xml = files["mitsuba"].read_text()
    bsdf_id = re.search(r'<bsdf type="hair" id="([^"]+)"', xml).group(1)
    curve = tmp / "curve.txt"
    curve.write_text("0 0 -3 0.5\n0 0 -1 0.5\n0 0 1 0.5\n0 0 3 0.5\n")
    scene_xml = tmp / "scene.xml"
    scene_xml.write_text(f"""<scene version="3.0.0">
    <include filename="{files['mitsuba'].name}"/>
    <integrator type="path"><integer name="max_depth" value="16"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="30"/>
        <transform name="to_world"><lookat origin="0, -12, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
            <rfilter type="box"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1, 1, 1"/></emitter>
    <shape type="bsplinecurve"><string name="filename" value="{curve.name}"/><ref id="{bsdf_id}"/></shape>
</scene>
""")
    scene = mi.load_file(str(scene_xml))
    bsdf = scene.shapes()[0].bsdf()
    p = mi.traverse(bsdf)
    want = doc["targets"]["mitsuba"]
    got = {
        "eta": float(p["eta"]),
        "longitudinal_roughness": float(p["longitudinal_roughness"]),
        "azimuthal_roughness": float(p["azimuthal_roughness"]),
        "scale_tilt": float(p["scale_tilt"]),
        "sigma_a": list(p["sigma_a.value"]),
    }
    checks = [("eta", want["int_ior"] / want["ext_ior"]),
              ("longitudinal_roughness", want["longitudinal_roughness"]),
              ("azimuthal_roughness", want["azimuthal_roughness"]),
              ("scale_tilt", want["scale_tilt"])]
    for k, v in checks:
        if abs(got[k] - v) > 1e-5 * max(1.0, abs(v)):
            failures.append(f"Mitsuba {k} = {got[k]}, JSON {v}")
    for g, w in zip(got["sigma_a"], want["sigma_a"]):
        if abs(g - w) > 1e-5 * max(1.0, abs(w)):
            failures.append(f"Mitsuba sigma_a = {got['sigma_a']}, JSON {want['sigma_a']}")

    ctx = mi.BSDFContext()

    def mi_eval(wi, wo):
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*wi)
        si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
        return np.array(bsdf.eval(ctx, si, mi.Vector3f(*wo)), dtype=float)

    tests = doc["tests"]
    largest = max(max(t["value"]) for t in tests)
    worst = {"near": 0.0, "far": 0.0}
    counted = {"near": 0, "far": 0}
    for t in tests:
        ours = np.array(t["value"])
        if t["kind"] == "near":
            theirs = mi_eval(t["wi_local"], t["wo_local"])
        else:
            ti, to, dp = (math.radians(t[k]) for k in ("theta_i_deg", "theta_o_deg", "dphi_deg"))
            theirs = np.zeros_like(ours)
            for g, w in zip(*gauss_legendre_gamma(t["panels"])):
                h = math.sin(g)
                wi = (-h * math.cos(ti), math.sin(ti), math.sqrt(max(0.0, 1 - h * h)) * math.cos(ti))
                phi_o = math.atan2(wi[2], wi[0]) + dp
                wo = (math.cos(to) * math.cos(phi_o), math.sin(to), math.cos(to) * math.sin(phi_o))
                theirs += w * mi_eval(wi, wo)
        for c, (o, m) in enumerate(zip(ours, theirs)):
            if o < TINY * largest:
                if abs(m - o) > TOLERANCE * TINY * largest:
                    failures.append(f"{t['kind']} test {t}: channel {c} Mitsuba {m:.6g}, ours {o:.6g}")
                continue
            rel = abs(m - o) / o
            counted[t["kind"]] += 1
            worst[t["kind"]] = max(worst[t["kind"]], rel)
            if rel > TOLERANCE:
                failures.append(f"{t['kind']} θi {t['theta_i_deg']} θo {t['theta_o_deg']:.2f} "
                                f"Δφ {t['dphi_deg']:.2f} h {t.get('h')}: channel {c} Mitsuba "
                                f"{m:.6g}, ours {o:.6g} ({100 * rel:.3f} %)")
    print(f"Mitsuba 3 {mi.__version__} hair plugin vs the fitted model: near field max relative "
          f"difference {100 * worst['near']:.4f} % over {counted['near']} values, far field (h "
          f"average) {100 * worst['far']:.4f} % over {counted['far']} values (tolerance "
          f"{100 * TOLERANCE:.0f} %)")
    if counted["near"] < 20 or counted["far"] < 6:
        failures.append(f"too few non-tiny test values: {counted}")

    image = np.array(mi.render(scene, spp=16))
    if image.shape != (16, 16, 3) or not np.all(np.isfinite(image)) or image.mean() <= 0.0:
        failures.append(f"render: shape {image.shape}, mean {image.mean()}")
    print(f"render: 16 x 16, mean {image.mean():.4f}, centre column mean "
          f"{image[:, 7:9].mean():.4f}")

    # --- pbrt-v4 and Blender: same numbers in each engine's units.
    pb = files["pbrt"].read_text()
    if 'Material "hair"' not in pb:
        failures.append("pbrt: no Material \"hair\"")

    def pbrt_value(name):
        m = re.search(r'"(?:float|rgb) ' + name + r'" \[ ([^\]]+) \]', pb)
        return [float(x) for x in m.group(1).split()]

    wp = doc["targets"]["pbrt"]
    for k in ("eta", "beta_m", "beta_n", "alpha"):
        if abs(pbrt_value(k)[0] - wp[k]) > 1e-5:
            failures.append(f"pbrt {k} {pbrt_value(k)} vs {wp[k]}")
    if np.max(np.abs(np.array(pbrt_value("sigma_a")) - wp["sigma_a"])) > 1e-5 * max(1, max(wp["sigma_a"])):
        failures.append(f"pbrt sigma_a {pbrt_value('sigma_a')} vs {wp['sigma_a']}")

    py = files["blender"].read_text()
    compile(py, str(files["blender"]), "exec")
    ns = {}
    exec("\n".join(l for l in py.splitlines()
                   if re.match(r"^(MATERIAL|SIGMA_A|BETA_M|BETA_N|IOR|OFFSET_RAD) =", l)), ns)
    wb = doc["targets"]["blender"]
    pairs = [("BETA_M", wb["Roughness"]), ("BETA_N", wb["Radial Roughness"]), ("IOR", wb["IOR"]),
             ("OFFSET_RAD", -math.radians(par["alpha_deg"]))]
    for k, v in pairs:
        if abs(ns[k] - v) > 1e-5:
            failures.append(f"blender {k} {ns[k]} vs {v}")
    if np.max(np.abs(np.array(ns["SIGMA_A"]) - wb["Absorption Coefficient"])) > 1e-5 * max(1, max(wb["Absorption Coefficient"])):
        failures.append(f"blender SIGMA_A {ns['SIGMA_A']}")

    return failures


if __name__ == "__main__":
    main()
