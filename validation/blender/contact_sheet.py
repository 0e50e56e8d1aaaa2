#!/usr/bin/env python3
"""Skin contact sheet: one Cycles sphere per Fitzpatrick entry, tiled into one labelled PNG.

    python3 validation/blender/contact_sheet.py --table out/fitzpatrick/profiles.bkt \
        --bpy target/bpy-venv/bin/python --baker target/release/baker -o DIR \
        [--xi 0.5] [--size 96] [--samples 16] [--exposure-ev 0]

Runs with the system python3 (numpy, mitsuba for reading EXR; no PIL, no matplotlib):
1. `BAKER export TABLE --to blender --entry ...` (default Subsurface Method, random-walk-skin)
   for the 42 entries typeT_ageA_xiX (T = I..VI, A = 20, 30, ..., 80, X = --xi) →
   DIR/work/skin_blender.py;
2. `BPY validation/blender/render_spheres.py DIR/work/skin_blender.py DIR/work/renders
   --size N --samples S --kind skin` (runs the exported script unchanged in bpy, renders one
   3 cm sphere per material, one sun at 45°, black world → DIR/work/renders/<material>.exr and
   report.json);
3. reads the EXRs (linear Rec.709, premultiplied alpha), composites them over a fixed grey
   background, applies ONE exposure to every sphere (scale 2^EV, default EV 0, i.e. the linear
   values as rendered), encodes with the sRGB transfer function (IEC 61966-2-1), 8 bit, and
   tiles them: rows = types I..VI, columns = ages 20..80, labels drawn with a built-in 5x7
   bitmap font → DIR/skin_contact_sheet.png (written atomically, PNG encoded with zlib).

Exits non-zero with a message if an entry is missing from the table, a sphere is not rendered,
or a render is non-finite or black. Prints the wall time.
"""

import argparse
import json
import os
import struct
import subprocess
import sys
import time
import zlib
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # validation/bkt.py

TYPES = ["I", "II", "III", "IV", "V", "VI"]
AGES = [20, 30, 40, 50, 60, 70, 80]
BACKGROUND_LINEAR = 0.05  # grey behind the spheres (linear; sRGB ≈ 63/255)
LABEL_LINEAR = 1.0  # white text
# A sphere is "black" if its mean linear luminance over its pixels is below this. The darkest
# entry (type VI, age 80) renders at ≈ 0.04 at EV 0 with the scene of render_spheres.py.
BLACK_LUMINANCE = 1e-3

# 5x7 glyphs, only the characters the labels use.
FONT = {
    "0": [".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."],
    "1": ["..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."],
    "2": [".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####"],
    "3": ["#####", "...#.", "..#..", "...#.", "....#", "#...#", ".###."],
    "4": ["...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#."],
    "5": ["#####", "#....", "####.", "....#", "....#", "#...#", ".###."],
    "6": ["..##.", ".#...", "#....", "####.", "#...#", "#...#", ".###."],
    "7": ["#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#..."],
    "8": [".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###."],
    "9": [".###.", "#...#", "#...#", ".####", "....#", "...#.", ".##.."],
    "I": [".###.", "..#..", "..#..", "..#..", "..#..", "..#..", ".###."],
    "V": ["#...#", "#...#", "#...#", "#...#", "#...#", ".#.#.", "..#.."],
    "E": ["#####", "#....", "#....", "####.", "#....", "#....", "#####"],
    "a": [".....", ".....", ".###.", "....#", ".####", "#...#", ".####"],
    "e": [".....", ".....", ".###.", "#...#", "#####", "#....", ".###."],
    "g": [".....", ".####", "#...#", "#...#", ".####", "....#", ".###."],
    "i": ["..#..", ".....", ".##..", "..#..", "..#..", "..#..", ".###."],
    "p": [".....", "####.", "#...#", "#...#", "####.", "#....", "#...."],
    "t": [".#...", ".#...", "###..", ".#...", ".#...", ".#..#", "..##."],
    "x": [".....", ".....", "#...#", ".#.#.", "..#..", ".#.#.", "#...#"],
    "y": [".....", "#...#", "#...#", "#...#", ".####", "....#", ".###."],
    "=": [".....", ".....", "#####", ".....", "#####", ".....", "....."],
    ".": [".....", ".....", ".....", ".....", ".....", ".##..", ".##.."],
    "-": [".....", ".....", ".....", "#####", ".....", ".....", "....."],
    "+": [".....", "..#..", "..#..", "#####", "..#..", "..#..", "....."],
    " ": [".....", ".....", ".....", ".....", ".....", ".....", "....."],
}
GLYPH_W, GLYPH_H, GLYPH_GAP = 5, 7, 1


def fail(msg):
    print(f"contact_sheet: error: {msg}", file=sys.stderr)
    sys.exit(1)


def text_mask(text, scale):
    """Boolean mask (h, w) of `text` in the bitmap font, each font pixel scale×scale."""
    missing = sorted({c for c in text if c not in FONT})
    if missing:
        raise ValueError(f"no glyph for {missing!r}")
    h = GLYPH_H
    w = len(text) * (GLYPH_W + GLYPH_GAP) - GLYPH_GAP
    m = np.zeros((h, max(w, 1)), dtype=bool)
    for k, ch in enumerate(text):
        x0 = k * (GLYPH_W + GLYPH_GAP)
        for y, row in enumerate(FONT[ch]):
            for x, c in enumerate(row):
                m[y, x0 + x] = c == "#"
    return np.kron(m, np.ones((scale, scale), dtype=bool))


def draw_text(img, text, x_center, y_center, scale, value):
    m = text_mask(text, scale)
    h, w = m.shape
    y0 = int(round(y_center - h / 2))
    x0 = int(round(x_center - w / 2))
    img[y0:y0 + h, x0:x0 + w][m] = value


def srgb_encode(linear):
    """IEC 61966-2-1 transfer function, linear [0, 1] → 8-bit."""
    x = np.clip(linear, 0.0, 1.0)
    v = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return np.round(v * 255.0).astype(np.uint8)


def write_png(path, rgb8):
    """8-bit RGB PNG (PNG spec: IHDR, one IDAT of filter-0 scanlines, IEND), atomically."""
    h, w, _ = rgb8.shape
    raw = b"".join(b"\x00" + rgb8[y].tobytes() for y in range(h))

    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data
                + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(png)
    os.replace(tmp, path)


def read_exr_rgba(path):
    """Linear float RGBA (h, w, 4) of an EXR, via Mitsuba's Bitmap (OpenEXR inside)."""
    import mitsuba as mi

    if mi.variant() is None:
        mi.set_variant("scalar_rgb")
    bmp = mi.Bitmap(str(path))
    if bmp.pixel_format() != mi.Bitmap.PixelFormat.RGBA:
        bmp = bmp.convert(mi.Bitmap.PixelFormat.RGBA, mi.Struct.Type.Float32, False)
    return np.array(bmp, dtype=np.float64)


def table_entries(table):
    from bkt import read_bkt_directory

    directory = read_bkt_directory(table)
    if directory.get("kind") != "skin_profiles":
        fail(f"{table} is a {directory.get('kind')!r} table, not skin_profiles")
    return json.loads(directory["metadata"]["entries"])


def run(cmd):
    print("+ " + " ".join(str(c) for c in cmd), flush=True)
    r = subprocess.run([str(c) for c in cmd])
    if r.returncode != 0:
        fail(f"command failed with exit status {r.returncode}: {cmd[0]}")


def main(argv):
    t0 = time.monotonic()
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--table", required=True, type=Path)
    ap.add_argument("--bpy", required=True, type=Path, help="python of the bpy venv")
    ap.add_argument("--baker", required=True, type=Path)
    ap.add_argument("-o", "--out", required=True, type=Path)
    ap.add_argument("--xi", default="0.5", help="ξ as spelled in the entry names (0, 0.5, 1)")
    ap.add_argument("--size", type=int, default=96)
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--exposure-ev", type=float, default=0.0,
                    help="one exposure for every sphere: linear × 2^EV before sRGB encoding")
    a = ap.parse_args(argv)

    entries = table_entries(a.table)
    grid = [[f"type{t}_age{age}_xi{a.xi}" for age in AGES] for t in TYPES]
    wanted = [n for row in grid for n in row]
    missing = [n for n in wanted if n not in entries]
    if missing:
        fail(f"{len(missing)} entries missing from {a.table}: {', '.join(missing[:6])}"
             + (" ..." if len(missing) > 6 else ""))

    work = a.out / "work"
    renders = work / "renders"
    work.mkdir(parents=True, exist_ok=True)
    script = work / "skin_blender.py"
    export = [a.baker, "export", a.table, "--to", "blender", "-o", script]
    for n in wanted:
        export += ["--entry", n]
    run(export)
    run([a.bpy, HERE / "render_spheres.py", script, renders, "--size", a.size,
         "--samples", a.samples, "--kind", "skin"])

    report = json.loads((renders / "report.json").read_text())
    mats = report["materials"]
    scale = 2.0 ** a.exposure_ev
    tiles = {}
    for n in wanted:
        if n not in mats:
            fail(f"no material {n!r} in {renders / 'report.json'} (the export script made "
                 f"{len(mats)}: {', '.join(list(mats)[:4])} ...)")
        if mats[n]["nodes"].get("subsurface_method") is None:
            fail(f"{n}: no Principled BSDF subsurface method reported")
        path = renders / mats[n]["image"]
        if not path.is_file():
            fail(f"sphere for {n} not rendered: {path} missing")
        px = read_exr_rgba(path)
        if px.shape != (a.size, a.size, 4):
            fail(f"{path}: shape {px.shape}, expected ({a.size}, {a.size}, 4)")
        if not np.isfinite(px).all():
            fail(f"{path}: non-finite pixels")
        mask = px[..., 3] > 0.5
        if mask.sum() < 0.2 * a.size * a.size:
            fail(f"{path}: sphere covers only {int(mask.sum())} pixels")
        lum = (px[..., :3][mask] @ np.array([0.2126, 0.7152, 0.0722])).mean()
        if not lum > BLACK_LUMINANCE:
            fail(f"{path}: sphere is black (mean linear luminance {lum:.3g})")
        # Premultiplied alpha over the grey background, then the one exposure.
        rgb = px[..., :3] + (1.0 - px[..., 3:4]) * BACKGROUND_LINEAR
        tiles[n] = rgb * scale

    # Layout (pixels): title band, column labels, then rows with a row label on the left.
    s = 2 if a.size >= 64 else 1  # font scale
    gap = max(4, a.size // 16)
    char_w = (GLYPH_W + GLYPH_GAP) * s
    left = max(len(f"type {t}") for t in TYPES) * char_w + 2 * gap
    title_h = GLYPH_H * s + 2 * gap
    col_h = GLYPH_H * s + 2 * gap
    width = left + len(AGES) * (a.size + gap) + gap
    height = title_h + col_h + len(TYPES) * (a.size + gap) + gap
    sheet = np.full((height, width, 3), BACKGROUND_LINEAR * scale)
    ev = f"{a.exposure_ev:+g}" if a.exposure_ev else "0"
    draw_text(sheet, f"xi={a.xi}   EV {ev}", width / 2, title_h / 2, s, LABEL_LINEAR)
    for j, age in enumerate(AGES):
        x = left + j * (a.size + gap)
        draw_text(sheet, f"age {age}", x + a.size / 2, title_h + col_h / 2, s, LABEL_LINEAR)
    for i, t in enumerate(TYPES):
        y = title_h + col_h + i * (a.size + gap)
        draw_text(sheet, f"type {t}", left / 2, y + a.size / 2, s, LABEL_LINEAR)
        for j in range(len(AGES)):
            x = left + j * (a.size + gap)
            sheet[y:y + a.size, x:x + a.size] = tiles[grid[i][j]]
    png = a.out / "skin_contact_sheet.png"
    write_png(png, srgb_encode(sheet))
    dt = time.monotonic() - t0
    print(f"contact_sheet: {len(wanted)} spheres ({a.size} px, {a.samples} samples, "
          f"Blender {'.'.join(map(str, report['blender_version']))}, "
          f"{mats[wanted[0]]['nodes']['subsurface_method']}), exposure EV {a.exposure_ev:g} "
          f"(×{scale:g}), sRGB 8 bit → {png} ({width}×{height}); wall time {dt:.1f} s")


if __name__ == "__main__":
    main(sys.argv[1:])
