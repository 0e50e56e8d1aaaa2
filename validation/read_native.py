#!/usr/bin/env python3
"""Independent reader of the baker's native tables, written from formats/FORMAT.md alone.

    read_bkt(path)   -> (kind, metadata, {name: np.ndarray})           # any .bkt
    read_bcsdf(path) -> (directory, f_normalised float32 [n_wi, n_variants, n_channels,
                         n_theta, n_phi])                               # a .bcsdf

Needs numpy and zstandard only (+ json, struct, zlib). f_normalised is decoded as the Rust
reader does (formats/src/bcsdf.rs, decode_values): un-shuffle the bytes, read f16 or f32
little-endian, widen to float32, multiply by the float32 scale of its (direction, variant,
channel) in float32 arithmetic, so the values agree bit for bit. Every check the layout
allows is made; a violation raises FormatError. `python3 validation/read_native.py FILE...`
prints a summary of each file.
"""
import json
import struct
import sys
import zlib

import numpy as np
import zstandard

# magic, version, flags, directory_compressed_len, directory_raw_len, payload_len,
# directory_crc32, reserved: the same 48 bytes in both formats.
HEADER = struct.Struct("<8sIIQQQII")
DTYPES = {"f64": "<f8", "f32": "<f4", "u32": "<u4", "u64": "<u8"}
BCSDF_DTYPES = {"f16": "<f2", "f32": "<f4"}


class FormatError(ValueError):
    """The bytes break the documented layout."""


def _check(cond, msg):
    if not cond:
        raise FormatError(msg)


def _frame(data, raw_len, crc, what):
    """One whole zstd frame that yields exactly raw_len bytes with CRC-32 crc."""
    _check(zstandard.frame_content_size(data) in (raw_len, -1), f"{what}: frame size")
    try:
        raw = zstandard.ZstdDecompressor().decompress(data, max_output_size=raw_len, allow_extra_data=False)
    except zstandard.ZstdError as e:
        raise FormatError(f"{what}: {e}") from None
    _check(len(raw) == raw_len, f"{what}: {len(raw)} bytes, {raw_len} declared")
    _check(zlib.crc32(raw) == crc, f"{what}: CRC-32 mismatch")
    return raw


def _open(path, magic):
    """(directory dict, payload bytes) of a file with the common 48-byte header."""
    with open(path, "rb") as f:
        buf = f.read()
    _check(len(buf) >= HEADER.size, "shorter than the header")
    m, version, flags, dc, dr, plen, dcrc, reserved = HEADER.unpack_from(buf)
    _check(m == magic, f"bad magic {m!r}, expected {magic!r}")
    _check(version == 1, f"version {version} is not supported")
    _check(flags == 0 and reserved == 0, "non-zero flags or reserved field")
    _check(len(buf) == HEADER.size + dc + plen, "file size disagrees with the header")
    raw = _frame(buf[HEADER.size : HEADER.size + dc], dr, dcrc, "directory")
    return json.loads(raw.decode("utf-8")), buf[HEADER.size + dc :]


def read_bkt(path):
    """(kind, metadata, {name: array}) of a .bkt file; arrays in file order, read-only."""
    d, payload = _open(path, b"BAKERTBL")
    _check(isinstance(d.get("kind"), str) and d["kind"], "missing or empty kind")
    _check("metadata" in d and isinstance(d.get("arrays"), list), "directory keys")
    arrays, end = {}, 0
    for e in d["arrays"]:
        name, shape = e["name"], [int(n) for n in e["shape"]]
        _check(e["dtype"] in DTYPES, f"{name}: unknown dtype {e['dtype']!r}")
        dt = np.dtype(DTYPES[e["dtype"]])
        _check(int(np.prod(shape, dtype=np.int64)) * dt.itemsize == e["raw_bytes"], f"{name}: raw_bytes")
        _check(e["offset"] == end, f"{name}: frames are not back to back")
        end = e["offset"] + e["compressed_bytes"]
        _check(end <= len(payload), f"{name}: frame past the payload")
        _check(name not in arrays, f"duplicate name {name!r}")
        raw = _frame(payload[e["offset"] : end], e["raw_bytes"], e["crc32"], name)
        arrays[name] = np.frombuffer(raw, dtype=dt).reshape(shape)
    _check(end == len(payload), "frames do not cover the payload")
    return d["kind"], d["metadata"], arrays


def read_bcsdf(path):
    """(directory, f_normalised) of a .bcsdf file; f_normalised is float32 [n_wi, n_variants,
    n_channels, n_theta, n_phi], value x scale[wi][variant][channel], sr^-1."""
    d, payload = _open(path, b"BAKERFIB")
    _check(d.get("kind") == "baker-fiber-bcsdf", f"kind {d.get('kind')!r}")
    res, nt, nph = d["res_deg"], d["n_theta"], d["n_phi"]
    _check(nt == round(180 / res) and nph == 2 * nt, "n_theta/n_phi disagree with res_deg")
    n_wi, nv, nc = len(d["wi_deg"]), len(d["variants"]), len(d["channels"])
    _check(d["dtype"] in BCSDF_DTYPES, f"unknown dtype {d['dtype']!r}")
    dt = np.dtype(BCSDF_DTYPES[d["dtype"]])
    _check(len(d["wi_map"]) == nt * nph, "wi_map length")
    _check(all((m & (2**30 - 1)) < n_wi for m in d["wi_map"]), "wi_map points past the stored directions")
    for k in ("scale", "albedo", "albedo_se"):
        _check(len(d[k]) == n_wi * nv * nc, f"{k} length")
    _check(len(d["area_um"]) == nph and len(d["chunks"]) == n_wi, "area_um or chunks length")
    scale = np.array(d["scale"], dtype=np.float64).astype(np.float32).reshape(n_wi, nv * nc)
    n = nv * nc * nt * nph
    out = np.empty((n_wi, nv * nc, nt * nph), dtype=np.float32)
    for i, c in enumerate(d["chunks"]):
        _check(c["raw_bytes"] == n * dt.itemsize, f"chunk {i}: raw_bytes")
        _check(c["offset"] + c["compressed_bytes"] <= len(payload), f"chunk {i}: past the payload")
        raw = _frame(payload[c["offset"] : c["offset"] + c["compressed_bytes"]], c["raw_bytes"], c["crc32"], f"chunk {i}")
        # Byte-shuffled: plane b holds byte b of every value; transpose back to values.
        planes = np.frombuffer(raw, dtype=np.uint8).reshape(dt.itemsize, n)
        values = np.ascontiguousarray(planes.T).view(dt).reshape(nv * nc, nt * nph)
        # float32 x float32 in float32, as Rust's `f16::to_f32() * s` / `f32 * s`.
        np.multiply(values.astype(np.float32), scale[i][:, None], out=out[i], dtype=np.float32)
    return d, out.reshape(n_wi, nv, nc, nt, nph)


def main(paths):
    for p in paths:
        if p.endswith(".bcsdf"):
            d, f = read_bcsdf(p)
            print(f"{p}: {d['kind']}, f_normalised {f.shape} {f.dtype}, variants {d['variants']}, "
                  f"channels {d['channels']}, res {d['res_deg']} deg, {d['dtype']} keep_bits {d['keep_bits']}")
        else:
            kind, meta, arrays = read_bkt(p)
            print(f"{p}: kind {kind}, {len(arrays)} arrays, metadata keys {sorted(meta) if isinstance(meta, dict) else meta}")


if __name__ == "__main__":
    main(sys.argv[1:])
