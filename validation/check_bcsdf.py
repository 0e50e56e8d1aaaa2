#!/usr/bin/env python3
"""Fiber BCSDF tables read without Rust: bakes a small fiber spec, decodes every `.bcsdf`
chunk with numpy + zstandard from the documented byte layout (formats/FORMAT.md, "Fiber
BCSDF tables"), and checks that

- the HDF5 file (h5py) holds exactly the same decoded values, albedo and projected width;
- dimension scales are attached (theta_i_deg, variant, channel, theta_o_deg, dphi_deg);
- every table is normalised: sum(f * solid angle) = 1 per channel (up to f16 rounding and the
  rounding to a quarter of each bin's standard error);
- undyed albedo is 1, and the manifest's SHA-256 match the files.

Usage: python3 validation/check_bcsdf.py --baker target/release/baker
"""
import argparse
import hashlib
import json
import struct
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path

import h5py
import numpy as np
import zstandard

SPEC = """version: 1
bake: {resolution_deg: 10, photons_per_direction: 8192, precision: f16}
fibers:
  - {name: silk, type: silk, section: {shape: silk}, seed: 2, sections: 2,
     sweep: {dyes: [reactive_blue_19], depth_of_shade_percent: [1], undyed: true}}
  - {name: poly, type: polyester, section: {shape: circle}}
"""


def read_bcsdf(path):
    b = Path(path).read_bytes()
    magic, version, flags, dc, dr, pl, crc, _ = struct.unpack_from("<8sIIQQQII", b, 0)
    assert magic == b"BAKERFIB" and version == 1, (magic, version)
    assert 48 + dc + pl == len(b), "size"
    d = zstandard.ZstdDecompressor().decompress(b[48 : 48 + dc], max_output_size=dr)
    assert zlib.crc32(d) == crc, "directory crc"
    meta = json.loads(d)
    payload = b[48 + dc :]
    nv, nc, nt, npp = len(meta["variants"]), len(meta["channels"]), meta["n_theta"], meta["n_phi"]
    dt = np.float16 if meta["dtype"] == "f16" else np.float32
    size = np.dtype(dt).itemsize
    out = []
    scale = np.array(meta["scale"], dtype=np.float32).reshape(-1, nv * nc)
    for i, c in enumerate(meta["chunks"]):
        raw = zstandard.ZstdDecompressor().decompress(
            payload[c["offset"] : c["offset"] + c["compressed_bytes"]], max_output_size=c["raw_bytes"]
        )
        assert zlib.crc32(raw) == c["crc32"], f"chunk {i} crc"
        n = len(raw) // size
        planes = np.frombuffer(raw, dtype=np.uint8).reshape(size, n)  # byte-shuffled
        vals = np.ascontiguousarray(planes.T).view(dt).reshape(nv * nc, nt * npp).astype(np.float32)
        vals = vals * scale[i][:, None]
        out.append(vals.reshape(nv, nc, nt, npp))
    return meta, np.stack(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--baker", required=True)
    a = ap.parse_args()
    fails = 0
    with tempfile.TemporaryDirectory() as tmp:
        spec = Path(tmp) / "bcsdf_small.yaml"
        spec.write_text(SPEC)
        subprocess.run([a.baker, "bake", "--quiet", "--out", tmp, str(spec)], check=True)
        root = Path(tmp) / "bcsdf_small"
        man = json.loads((root / "manifest.json").read_text())
        for f in man["files"]:
            h = hashlib.sha256((root / f["path"]).read_bytes()).hexdigest()
            if h != f["sha256"]:
                print(f"FAIL sha256 {f['path']}")
                fails += 1
        for entry, tables in [("silk", ["section-00", "section-01", "average"]), ("poly", ["section-00"])]:
            with h5py.File(root / entry / f"{entry}.h5", "r") as h:
                for t in tables:
                    meta, vals = read_bcsdf(root / entry / f"{t}.bcsdf")
                    g = h[t]
                    f5 = g["f_normalised"][...]
                    ok = np.array_equal(f5, vals)
                    ok &= np.array_equal(g["albedo"][...].ravel(), np.array(meta["albedo"], np.float32))
                    ok &= np.array_equal(g["area_um"][...], np.array(meta["area_um"]))
                    labels = [g["f_normalised"].dims[i][0].name.rsplit("/", 1)[-1] for i in range(5)]
                    ok &= labels == ["theta_i_deg", "variant", "channel", "theta_o_deg", "dphi_deg"]
                    res = meta["res_deg"]
                    t0 = np.radians(-90 + res * np.arange(meta["n_theta"]))
                    dw = np.radians(res) * (np.sin(t0 + np.radians(res)) - np.sin(t0))
                    norm = (vals * dw[None, None, None, :, None]).sum(axis=(3, 4))
                    alb = np.array(meta["albedo"]).reshape(norm.shape)
                    live = alb > 0
                    nerr = np.abs(norm[live] - 1).max()
                    # f16 at 8 kept bits (≤ 2e-3), plus rounding each value within a quarter of
                    # its bin's standard error (bake.quantise_to_se, default 0.25): zero-mean
                    # errors whose sum over a slice is ~0.1·sqrt(sum SE^2) ≈ 1e-3 at 8192 photons.
                    ok &= nerr < 5e-3
                    undyed = [i for i, v in enumerate(meta["variants"]) if v == "undyed"]
                    aerr = np.abs(alb[:, undyed, :] - 1).max() if undyed else 0.0
                    ok &= aerr < 1e-5
                    print(
                        f"{'ok  ' if ok else 'FAIL'} {entry}/{t}: {vals.shape[0]} stored directions, "
                        f"h5py == numpy decode: {np.array_equal(f5, vals)}, dims {labels}, "
                        f"max |sum f dw - 1| {nerr:.1e}, max |undyed albedo - 1| {aerr:.1e}"
                    )
                    fails += not ok
    sys.exit(1 if fails else 0)


if __name__ == "__main__":
    main()
