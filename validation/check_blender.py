#!/usr/bin/env python3
"""Blender runs every `baker export --to blender` script unchanged, builds the materials with
the export's numbers, and renders them (issue 19, item 3).

    python3 validation/check_blender.py --baker target/release/baker [--python target/bpy-venv/bin/python]

Bakes specs/quickstart.yaml (skin types I, III, VI) and specs/quickstart-fiber.yaml (one dyed
polyester) into a temporary folder, exports the skin table `--to blender` with each `--method`
(burley, random-walk, random-walk-skin) and the fiber table `--to blender`, and runs each script
in Blender's Python module (bpy, a subprocess of the venv made by validation/blender/venv.sh)
through validation/blender/render_spheres.py, which renders a 64 px sphere (skin) or a patch of
hair curves (fiber) per material, 16 samples, Cycles on the CPU. Checks:

- every script runs and makes one material per entry, Principled BSDF linked to the output;
- the node values equal the parameters recomputed here, independently of the Rust code, from
  the `--to burley` JSON (A, d, eta, F0) with Cycles' conventions (see
  baker/src/export/skin/blender.rs; sources: intern/cycles/kernel/closure/bssrdf.h,
  subsurface_random_walk.h): C = A/(1 - F0); Burley radius 4 pi d; random walk 4 pi l;
  skin walk l / sqrt(3 (1 - a')), l = d (1.9 - C + 3.5 (C - 0.8)^2), a' Cycles' dipole albedo;
  and the hair node values equal the `--to chiang` JSON (Offset = -alpha);
- each render is finite and not black (every channel's mean over the object > 1e-3);
- skin colour ordering: luminance type I > III > VI for every method, and type I is red
  (R > G > B), as the baked albedos are.
Exit status 1 on any failure. Budget: about 20 s on 2 cores (bpy already installed).
"""

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RENDER = ROOT / "validation" / "blender" / "render_spheres.py"
METHODS = {"burley": "BURLEY", "random-walk": "RANDOM_WALK", "random-walk-skin": "RANDOM_WALK_SKIN"}
LUMA = (0.2126, 0.7152, 0.0722)  # Rec. 709 luminance of linear sRGB

failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def close(a, b, rel=2e-5, abs_=1e-7):
    a = a if isinstance(a, (list, tuple)) else [a]
    b = b if isinstance(b, (list, tuple)) else [b]
    return len(a) == len(b) and all(abs(x - y) <= abs_ + rel * abs(y) for x, y in zip(a, b))


def dipole_alpha_prime(rd, eta):
    """Cycles bssrdf.h: bssrdf_dipole_compute_alpha_prime after bssrdf_setup's IOR clamp."""
    eta = min(max(eta, 1.01), 3.8)
    inv = 1.0 / eta
    f_dr = inv * (-1.440 * inv + 0.710) + 0.668 + 0.0636 * eta
    fourthird_a = (4.0 / 3.0) * (1.0 + f_dr) / (1.0 - f_dr)
    if rd < 1e-4:
        return 0.0
    if rd >= 0.995:
        return 0.999999
    x0, x1 = 0.0, 1.0
    for _ in range(12):
        xmid = 0.5 * (x0 + x1)
        s = math.sqrt(3.0 * (1.0 - xmid))
        if 0.5 * xmid * (1.0 + math.exp(-fourthird_a * s)) * math.exp(-s) < rd:
            x0 = xmid
        else:
            x1 = xmid
    return xmid


def expected_skin(entry, method):
    c = [min(max(a / (1.0 - entry["f0"]), 0.0), 1.0) for a in entry["A_rgb"]]
    radius = []
    for ck, d in zip(c, entry["d_mm_rgb"]):
        l_mm = d * (1.9 - ck + 3.5 * (ck - 0.8) ** 2)
        if method == "burley":
            radius.append(4.0 * math.pi * d)
        elif method == "random-walk":
            radius.append(4.0 * math.pi * l_mm)
        else:
            radius.append(l_mm / math.sqrt(3.0 * (1.0 - dipole_alpha_prime(ck, entry["eta"]))))
    return c, radius


def run(cmd, **kw):
    p = subprocess.run([str(x) for x in cmd], capture_output=True, text=True, **kw)
    if p.returncode != 0:
        sys.stderr.write(p.stdout[-3000:] + p.stderr[-3000:])
    return p


def render(python, script, out, kind):
    p = run([python, RENDER, script, out, "--size", 64, "--samples", 16, "--kind", kind])
    check(p.returncode == 0, f"bpy runs {Path(script).name} unchanged")
    if p.returncode != 0:
        return None
    return json.loads((Path(out) / "report.json").read_text())


def check_skin(python, baker, table, tmp):
    burley = json.loads(run([baker, "export", table, "--to", "burley"]).stdout)
    entries = {e["name"]: e for e in burley["entries"]}
    for method, enum in METHODS.items():
        script = tmp / f"skin_{method}.py"
        p = run([baker, "export", table, "--to", "blender", "--method", method, "-o", script, "-q"])
        check(p.returncode == 0, f"baker export --to blender --method {method}")
        report = render(python, script, tmp / f"render_{method}", "skin")
        if report is None:
            continue
        mats = report["materials"]
        check(sorted(mats) == sorted(entries), f"{method}: one material per entry ({len(mats)})")
        for name, m in mats.items():
            n, e = m["nodes"], entries[name]
            colour, radius = expected_skin(e, method)
            ok = (n["subsurface_method"] == enum and n["linked_to_output"]
                  and close(n["Base Color"][:3], colour) and close(n["Subsurface Radius"], radius)
                  and close(n["Subsurface Scale"], 0.001) and close(n["Subsurface Weight"], 1.0)
                  and close(n["IOR"], e["eta"]) and close(n["Subsurface IOR"], e["eta"])
                  and close(n["Subsurface Anisotropy"], 0.0))
            check(ok, f"{method} {name}: nodes {n['subsurface_method']}, Base Color "
                      f"{[round(x, 4) for x in n['Base Color'][:3]]}, Radius "
                      f"{[round(x, 4) for x in n['Subsurface Radius']]} mm (expected "
                      f"{[round(x, 4) for x in radius]})")
            rgb = m["mean_rgb"]
            check(m["finite"] and m["object_pixels"] > 1000 and min(rgb) > 1e-3,
                  f"{method} {name}: render finite, not black, mean RGB "
                  f"{[round(x, 4) for x in rgb]} over {m['object_pixels']} px")
        luma = {k: sum(w * x for w, x in zip(LUMA, v["mean_rgb"])) for k, v in mats.items()}
        order = [k for k in ("typeI", "typeIII", "typeVI") if k in luma]
        check(len(order) == 3 and luma[order[0]] > luma[order[1]] > luma[order[2]],
              f"{method}: luminance I > III > VI: "
              + ", ".join(f"{k} {luma[k]:.4f}" for k in order))
        r, g, b = mats["typeI"]["mean_rgb"] if "typeI" in mats else (0, 0, 0)
        check(r > g > b, f"{method}: type I renders red (R {r:.4f} > G {g:.4f} > B {b:.4f})")


def check_fiber(python, baker, table, tmp):
    chiang = json.loads(run([baker, "export", table, "--to", "chiang", "-q"]).stdout)
    p = chiang["parameters"]
    script = tmp / "fiber_blender.py"
    check(run([baker, "export", table, "--to", "blender", "-o", script, "-q"]).returncode == 0,
          "baker export fiber --to blender")
    report = render(python, script, tmp / "render_fiber", "fiber")
    if report is None:
        return
    mats = report["materials"]
    check(len(mats) == 1, f"fiber: one material ({list(mats)})")
    for name, m in mats.items():
        n = m["nodes"]
        ok = (n["parametrization"] == "ABSORPTION" and n.get("model", "CHIANG") == "CHIANG"
              and close(n["Absorption Coefficient"], p["sigma_a"], rel=1e-5)
              and close(n["Roughness"], p["beta_m"], rel=1e-5)
              and close(n["Radial Roughness"], p["beta_n"], rel=1e-5)
              and close(n["IOR"], p["eta"], rel=1e-5) and close(n["Coat"], 0.0)
              and close(n["Offset"], -math.radians(p["alpha_deg"]), rel=1e-5, abs_=1e-6))
        check(ok and m["assigned"], f"fiber {name}: hair nodes equal the Chiang fit {n}")
        rgb = m["mean_rgb"]
        check(m["finite"] and m["object_pixels"] > 500 and min(rgb) > 1e-3,
              f"fiber {name}: render finite, not black, mean RGB {[round(x, 4) for x in rgb]}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baker", default=str(ROOT / "target" / "release" / "baker"))
    ap.add_argument("--python", default=str(ROOT / "target" / "bpy-venv" / "bin" / "python"),
                    help="a Python with bpy (validation/blender/venv.sh makes it)")
    a = ap.parse_args()
    if run([a.python, "-c", "import bpy"]).returncode != 0:
        sys.exit(f"error: {a.python} cannot import bpy; run validation/blender/venv.sh")
    t0 = time.time()
    with tempfile.TemporaryDirectory(prefix="check_blender_") as tmp:
        tmp = Path(tmp)
        p = run([a.baker, "bake", ROOT / "specs/quickstart.yaml",
                 ROOT / "specs/quickstart-fiber.yaml", "-o", tmp / "bake"])
        check(p.returncode == 0, "bake specs/quickstart.yaml specs/quickstart-fiber.yaml")
        if p.returncode == 0:
            check_skin(a.python, a.baker, tmp / "bake/quickstart/profiles.bkt", tmp)
            fibers = sorted((tmp / "bake/quickstart-fiber").glob("*/*.bcsdf"))
            check(len(fibers) >= 1, f"fiber table baked ({len(fibers)})")
            if fibers:
                check_fiber(a.python, a.baker, fibers[0], tmp)
    print(f"check_blender: {len(failures)} failure(s), {time.time() - t0:.1f} s")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
