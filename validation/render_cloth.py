#!/usr/bin/env python3
"""Cloth renders: every fiber table through the Mitsuba 3 plugin `baker_bcsdf`, and beside it the
Chiang fit of the same table (`baker export --to mitsuba`, Mitsuba's `hair` plugin).

How to run (from the repository root, after `pip install ./formats/python`):

    python3 validation/render_cloth.py --baker target/release/baker --tables out/fibers -o DIR
    python3 validation/render_cloth.py --quick ...     # 64 px, 8 spp (CI)

The scene (written to DIR/scene/ as Mitsuba XML with its curve files, so it can be rendered
again with `mitsuba DIR/scene/<fiber>_table.xml` once the plugin is registered, or read):
  - a plain weave of monofilaments: 2 x N `bsplinecurve` fibers of radius R = 0.01 (scene
    units), warp along world x at y = j p, weft along y at x = i p, spacing p = 3 R, each
    undulating over and under the other (height +-1.2 R cos(pi s / p + k pi), so crossing
    fibers clear each other by 0.4 R); the patch is 0.5 x 0.5, the cloth plane z = 0;
  - a camera 0.5 from the centre, 50 deg above the plane, looking along +y at the centre,
    fov 30 deg (about 9 warp fibers across; the patch fills the frame), box filter, path
    tracer (max depth 32);
  - light: a `directional` emitter of irradiance 4 from 40 deg above the plane, behind the
    camera's right shoulder (so the R lobe's highlight and the TT forward scattering both show
    on the undulations), plus a dim `constant` environment (0.05).
The fiber axis (the table's +z, the tip for cuticle scales) is each curve's direction, first
control point to last: warp +x, weft +y; the sections' `up` is world +z (the cloth normal).

Per fiber type the script writes DIR/<fiber>_table.png, DIR/<fiber>_chiang.png, the pair side
by side DIR/<fiber>_pair.png (sRGB, 8 bit, clipped at 1), the linear images as .exr, and
DIR/cloth.json + DIR/cloth.md with the mean absolute difference of the two renders:
  - mad_linear: mean over pixels and R, G, B of |table - chiang| in linear radiance;
  - mad_rel: that divided by the mean of the table render (the fraction of its brightness);
  - mad_srgb8: the same on the 8-bit sRGB images (0-255), what the eye compares.
  - mad_block_rel: mad_rel of the images averaged over (res/16)^2-pixel blocks first: the
    difference of the pattern and brightness, with most pixel noise averaged out.
The noise floor of each (mad_noise_rel, mad_block_noise_rel) is the same measure between two
table renders of different seeds: a MAD near its floor says the renders differ by noise only.

Variants: renders in llvm_ad_rgb (the plugin's batched native calls; scalar_rgb works but takes
~10x longer). A table of several dye variants renders its first dyed one unless `--variant
FIBER=NAME` says otherwise; entry folders with several sections render average.bcsdf.
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

R = 0.01           # fiber radius (scene units)
PITCH = 3.0 * R    # spacing of the fibers of each direction
HALF = 0.25        # half-size of the patch
AMP = 1.2 * R      # undulation amplitude


def weave_curves():
    """Control points of the plain weave: (warp, weft), each a list of [m, 4] arrays (x, y, z, r)."""
    n = int(HALF / PITCH)
    s = np.arange(-HALF, HALF + 1e-9, PITCH / 4)
    warp, weft = [], []
    for k in range(-n, n + 1):
        c = k * PITCH
        z = AMP * np.cos(math.pi * s / PITCH + k * math.pi)
        warp.append(np.stack([s, np.full_like(s, c), z, np.full_like(s, R)], 1))
        weft.append(np.stack([np.full_like(s, c), s, -z, np.full_like(s, R)], 1))
    return warp, weft


def write_curves(path, curves):
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        fh.write("\n\n".join("\n".join(" ".join(f"{v:.6f}" for v in p) for p in c) for c in curves))
        fh.write("\n")
    os.replace(tmp, path)


def _camera(res, spp, fov=30.0, elev_deg=50.0, dist=0.5):
    e = math.radians(elev_deg)
    origin = [0.0, -dist * math.cos(e), dist * math.sin(e)]
    return (f'<sensor type="perspective"><float name="fov" value="{fov}"/>'
            f'<transform name="to_world"><lookat origin="{origin[0]}, {origin[1]}, {origin[2]}" '
            'target="0, 0, 0" up="0, 0, 1"/></transform>'
            f'<sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>'
            f'<film type="hdrfilm"><integer name="width" value="{res}"/><integer name="height" value="{res}"/>'
            '<rfilter type="box"/><string name="pixel_format" value="rgb"/></film></sensor>')


def _bsdf_xml(bsdf):
    """A bsdf dict {type: baker_bcsdf, filename, variant} as XML, or a <ref id=...>."""
    if "ref" in bsdf:
        return f'<ref id="{bsdf["ref"]}"/>'
    v = bsdf.get("variant", 0)
    vx = (f'<integer name="variant" value="{v}"/>' if isinstance(v, int)
          else f'<string name="variant" value="{v}"/>')
    return (f'<bsdf type="{bsdf["type"]}"><string name="filename" value="{os.path.abspath(bsdf["filename"])}"/>'
            f'{vx}</bsdf>')


def scene_xml(curve_dir, bsdf, res, spp, lights, include=None, integrator=None):
    integ = integrator or '<integrator type="path"><integer name="max_depth" value="32"/></integrator>'
    inc = f'<include filename="{os.path.abspath(include)}"/>' if include else ""
    shapes = "".join(
        f'<shape type="bsplinecurve"><string name="filename" value="{os.path.join(os.path.abspath(curve_dir), n)}.txt"/>'
        f'{_bsdf_xml(bsdf)}</shape>' for n in ("warp", "weft"))
    return f'<scene version="3.0.0">{inc}{integ}{_camera(res, spp)}{lights}{shapes}</scene>'


CLOTH_LIGHTS = ('<emitter type="directional"><vector name="direction" value="{dx}, {dy}, {dz}"/>'
                '<rgb name="irradiance" value="4"/></emitter>'
                '<emitter type="constant"><rgb name="radiance" value="0.05"/></emitter>')


def cloth_lights():
    e, a = math.radians(40.0), math.radians(-60.0)     # light from behind-right of the camera
    d = -np.array([math.cos(e) * math.sin(a), -math.cos(e) * math.cos(a), math.sin(e)])
    return CLOTH_LIGHTS.format(dx=d[0], dy=d[1], dz=d[2])


def ensure_curves(curve_dir):
    os.makedirs(curve_dir, exist_ok=True)
    warp, weft = weave_curves()
    write_curves(os.path.join(curve_dir, "warp.txt"), warp)
    write_curves(os.path.join(curve_dir, "weft.txt"), weft)


_FURNACE_DIR = None


def furnace_scenes(mi, bsdf, res, spp):
    """(white-furnace scene, depth-AOV scene) of the weave made of `bsdf` (a dict): a uniform
    `constant` emitter of radiance 1, path tracer of unlimited depth (Russian roulette from
    depth 5, Mitsuba's default), for validation/check_mitsuba_bcsdf.py."""
    global _FURNACE_DIR
    if _FURNACE_DIR is None:
        _FURNACE_DIR = tempfile.mkdtemp(prefix="baker-furnace-")
        ensure_curves(_FURNACE_DIR)
    light = '<emitter type="constant"><rgb name="radiance" value="1"/></emitter>'
    path = '<integrator type="path"><integer name="max_depth" value="-1"/></integrator>'
    aov = '<integrator type="aov"><string name="aovs" value="dd.y:depth"/></integrator>'
    return (mi.load_string(scene_xml(_FURNACE_DIR, bsdf, res, spp, light, integrator=path)),
            mi.load_string(scene_xml(_FURNACE_DIR, bsdf, res, 1, light, integrator=aov)))


def srgb8(img):
    x = np.clip(img, 0.0, 1.0)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


def write_png(mi, path, img8):
    tmp = path + ".tmp.png"
    mi.Bitmap(np.ascontiguousarray(img8), mi.Bitmap.PixelFormat.RGB).write(tmp)
    os.replace(tmp, path)


def write_exr(mi, path, img):
    tmp = path + ".tmp.exr"
    mi.Bitmap(np.ascontiguousarray(img.astype(np.float32)), mi.Bitmap.PixelFormat.RGB).write(tmp)
    os.replace(tmp, path)


def pick_variant(table, override):
    if override is not None:
        return override
    for v in table.variants:
        if v != "undyed":
            return v
    return table.variants[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baker", default="target/release/baker")
    ap.add_argument("--tables", default="out/fibers", help="folder of baked fiber entries")
    ap.add_argument("--fibers", default="polyester,silk,cotton,wool")
    ap.add_argument("--variant", action="append", default=[], help="FIBER=VARIANT (repeatable)")
    ap.add_argument("-o", "--out", required=True)
    ap.add_argument("--quick", action="store_true", help="64 px, 8 spp (CI); default 128 px, 32 spp")
    ap.add_argument("--res", type=int)
    ap.add_argument("--spp", type=int)
    args = ap.parse_args()
    res = args.res or (64 if args.quick else 128)
    spp = args.spp or (8 if args.quick else 32)
    overrides = dict(v.split("=", 1) for v in args.variant)

    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    from baker_formats import BcsdfTable
    from baker_formats import mitsuba as bm

    bm.enable_jit_evaluation()
    bm.register()

    out = os.path.abspath(args.out)
    scene_dir = os.path.join(out, "scene")
    ensure_curves(scene_dir)
    rows = []
    t_all = time.time()
    for fiber in [f for f in args.fibers.split(",") if f]:
        entry = os.path.join(args.tables, fiber)
        path = bm.resolve_path(entry)
        table = BcsdfTable(path)
        variant = pick_variant(table, overrides.get(fiber))
        bm.resolve_variant(table, variant)
        hair = os.path.join(scene_dir, f"{fiber}_hair.xml")
        ex = subprocess.run([args.baker, "export", path, "--to", "mitsuba", "--entry", variant, "-o", hair],
                            check=True, capture_output=True, text=True)
        fit = ex.stderr.strip().splitlines()[-1] if ex.stderr.strip() else ""
        import xml.etree.ElementTree as ET
        hair_id = ET.parse(hair).getroot().find("bsdf").get("id")
        lights = cloth_lights()
        table_bsdf = {"type": bm.PLUGIN, "filename": path, "variant": variant}
        xmls = {
            "table": scene_xml(scene_dir, table_bsdf, res, spp, lights),
            "chiang": scene_xml(scene_dir, {"ref": hair_id}, res, spp, lights, include=hair),
        }
        imgs, secs = {}, {}
        for kind, x in xmls.items():
            with open(os.path.join(scene_dir, f"{fiber}_{kind}.xml"), "w") as fh:
                fh.write(x)
            scene = mi.load_string(x)
            t0 = time.time()
            imgs[kind] = np.array(mi.render(scene, seed=1), dtype=np.float64)
            secs[kind] = time.time() - t0
        t0 = time.time()
        noise = np.array(mi.render(mi.load_string(xmls["table"]), seed=2), dtype=np.float64)
        secs["noise"] = time.time() - t0
        a, b = imgs["table"], imgs["chiang"]
        mad = float(np.abs(a - b).mean())
        mean = float(a.mean())
        k = max(1, res // 16)
        blk = lambda x: x[: res // k * k, : res // k * k].reshape(res // k, k, res // k, k, 3).mean(axis=(1, 3))
        row = dict(fiber=fiber, table=os.path.relpath(path), variant=variant, chiang_fit=fit,
                   res=res, spp=spp, mean_table=mean, mean_chiang=float(b.mean()),
                   mad_linear=mad, mad_rel=mad / mean,
                   mad_srgb8=float(np.abs(srgb8(a).astype(float) - srgb8(b).astype(float)).mean()),
                   mad_noise_rel=float(np.abs(a - noise).mean()) / mean,
                   block_px=k, mad_block_rel=float(np.abs(blk(a) - blk(b)).mean()) / mean,
                   mad_block_noise_rel=float(np.abs(blk(a) - blk(noise)).mean()) / mean,
                   seconds={k: round(v, 2) for k, v in secs.items()})
        rows.append(row)
        for kind, img in imgs.items():
            write_png(mi, os.path.join(out, f"{fiber}_{kind}.png"), srgb8(img))
            write_exr(mi, os.path.join(out, f"{fiber}_{kind}.exr"), img)
        gap = np.full((res, max(2, res // 32), 3), 255, np.uint8)
        write_png(mi, os.path.join(out, f"{fiber}_pair.png"), np.concatenate([srgb8(a), gap, srgb8(b)], 1))
        print(f"{fiber} ({variant}): mean {mean:.4f} (table) {b.mean():.4f} (chiang); MAD linear "
              f"{mad:.4f} = {mad / mean:.3f} of the mean (noise floor {row['mad_noise_rel']:.3f}), "
              f"sRGB8 {row['mad_srgb8']:.2f}; on {k}x{k} blocks {row['mad_block_rel']:.3f} (noise floor "
              f"{row['mad_block_noise_rel']:.3f}); {secs['table']:.1f} s + {secs['chiang']:.1f} s", flush=True)
    tmp = os.path.join(out, "cloth.json.tmp")
    with open(tmp, "w") as fh:
        json.dump(rows, fh, indent=1)
    os.replace(tmp, os.path.join(out, "cloth.json"))
    md = ["| fiber | variant | table | mean (table) | mean (Chiang) | MAD linear | MAD / mean | noise floor "
          "| MAD / mean, blocks | noise floor, blocks | MAD sRGB8 |",
          "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        md.append(f"| {r['fiber']} | {r['variant']} | `{r['table']}` | {r['mean_table']:.4f} | {r['mean_chiang']:.4f} | "
                  f"{r['mad_linear']:.4f} | {r['mad_rel']:.3f} | {r['mad_noise_rel']:.3f} | {r['mad_block_rel']:.3f} | "
                  f"{r['mad_block_noise_rel']:.3f} | {r['mad_srgb8']:.2f} |")
    md.append("")
    md.append(f"{res} x {res} px, {spp} spp, llvm_ad_rgb; `python3 validation/render_cloth.py "
              f"{'--quick ' if args.quick else ''}--tables {args.tables} -o {args.out}`. MAD over pixels and "
              "R, G, B; linear radiance unless sRGB8; blocks: both images averaged over "
              f"{max(1, res // 16)} x {max(1, res // 16)} px blocks first (the pattern, not the pixel noise). "
              "Noise floor: the same measure between two table renders of different seeds.")
    tmp = os.path.join(out, "cloth.md.tmp")
    with open(tmp, "w") as fh:
        fh.write("\n".join(md) + "\n")
    os.replace(tmp, os.path.join(out, "cloth.md"))
    print(f"wrote {out}/cloth.json, cloth.md, *_pair.png ({time.time() - t_all:.0f} s)")


if __name__ == "__main__":
    sys.exit(main())
