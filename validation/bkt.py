#!/usr/bin/env python3
"""Standalone reader of the baker's native tables (.bkt), for numpy.

Layout: formats/FORMAT.md, section "Native tables (.bkt)" (Rust side: formats/src/table.rs).
Needs numpy and zstandard (pip install -r validation/requirements.txt).

    from bkt import read_bkt
    kind, metadata, arrays = read_bkt("out/profiles.bkt")   # arrays: {name: np.ndarray}

Everything is checked as in Rust: magic, version, flags, lengths, one zstd frame per part,
shapes against sizes, back-to-back frames, and the CRC-32 (zlib.crc32) of the directory and
of every array. Any inconsistency raises BktError.

Command line: `python3 validation/bkt.py FILE [FILE...]` lists each file's kind, metadata and
arrays (dtype, shape, attributes, min/max); `--no-data` lists from the directory only.
"""

import json
import struct
import sys
import zlib

import numpy as np
import zstandard

MAGIC = b"BAKERTBL"
VERSION = 1
# magic, version, flags, directory_compressed_len, directory_raw_len, payload_len,
# directory_crc32, reserved
HEADER = struct.Struct("<8sIIQQQII")
assert HEADER.size == 48
DTYPES = {"f64": np.dtype("<f8"), "f32": np.dtype("<f4"), "u32": np.dtype("<u4"), "u64": np.dtype("<u8")}


class BktError(ValueError):
    """The bytes are not a valid .bkt table."""


def _frame(data, raw_len, what):
    """Decompresses the single zstd frame `data`, which must yield exactly `raw_len` bytes."""
    try:
        declared = zstandard.frame_content_size(data)
    except zstandard.ZstdError as e:
        raise BktError(f"{what}: not a zstd frame ({e})") from None
    if declared not in (-1, raw_len):  # -1: the frame does not record its size
        raise BktError(f"{what}: the zstd frame holds {declared} bytes, the file declares {raw_len}")
    try:
        raw = zstandard.ZstdDecompressor().decompress(
            data, max_output_size=raw_len, allow_extra_data=False
        )
    except zstandard.ZstdError as e:
        raise BktError(f"{what}: zstd decompression failed ({e})") from None
    if len(raw) != raw_len:
        raise BktError(f"{what}: decompressed to {len(raw)} bytes, the file declares {raw_len}")
    return raw


def _parse(buf, with_data=True):
    """(directory dict, {name: ndarray} or None) from the bytes of a file."""
    if len(buf) < HEADER.size:
        raise BktError(f"{len(buf)} bytes is shorter than the {HEADER.size}-byte header")
    magic, version, flags, dir_c, dir_raw, payload_len, dir_crc, reserved = HEADER.unpack_from(buf)
    if magic != MAGIC:
        raise BktError('bad magic (expected "BAKERTBL")')
    if version != VERSION:
        raise BktError(f"format version {version} is not supported (this reader: {VERSION})")
    if flags != 0 or reserved != 0:
        raise BktError(f"flags {flags:#x} / reserved {reserved:#x} must be 0 in version 1")
    if HEADER.size + dir_c + payload_len != len(buf):
        raise BktError(
            f"header declares a {dir_c}-byte directory and a {payload_len}-byte payload, but "
            f"{len(buf) - HEADER.size} bytes follow the header (truncated or trailing data)"
        )
    dir_end = HEADER.size + dir_c
    dir_bytes = _frame(buf[HEADER.size:dir_end], dir_raw, "the directory")
    if zlib.crc32(dir_bytes) != dir_crc:
        raise BktError(f"directory CRC-32 is {zlib.crc32(dir_bytes):08x}, the file stores {dir_crc:08x}")
    try:
        directory = json.loads(dir_bytes.decode("utf-8"))
        kind, entries = directory["kind"], directory["arrays"]
        directory["metadata"]
    except (UnicodeDecodeError, ValueError, KeyError, TypeError) as e:
        raise BktError(f"directory is not valid JSON of the format: {e!r}") from None
    if not isinstance(kind, str) or not kind or not isinstance(entries, list):
        raise BktError("directory: kind must be a non-empty string and arrays a list")

    payload = memoryview(buf)[dir_end:]
    arrays = {} if with_data else None
    seen = set()
    offset = 0
    for i, e in enumerate(entries):
        try:
            name, code, shape = e["name"], e["dtype"], [int(d) for d in e["shape"]]
            off, comp, raw_len, crc = (int(e[k]) for k in ("offset", "compressed_bytes", "raw_bytes", "crc32"))
        except (KeyError, TypeError, ValueError) as err:
            raise BktError(f"array #{i}: bad directory entry ({err!r})") from None
        what = f"array {name!r}"
        if not isinstance(name, str) or any(s in ("", ".", "..") for s in name.split("/")):
            raise BktError(f"array #{i}: invalid name {name!r}")
        if name in seen:
            raise BktError(f"duplicate array name {name!r}")
        seen.add(name)
        if code not in DTYPES:
            raise BktError(f"{what}: unknown dtype {code!r} (expected f64, f32, u32 or u64)")
        dtype = DTYPES[code]
        if any(d < 0 for d in shape) or int(np.prod(shape, dtype=object)) * dtype.itemsize != raw_len:
            raise BktError(f"{what}: shape {shape} of {code} does not match raw_bytes = {raw_len}")
        if off != offset:
            raise BktError(f"{what}: offset {off} but frames must be back to back (expected {offset})")
        if comp < 0 or off + comp > payload_len:
            raise BktError(f"{what}: frame at {off} + {comp} bytes runs past the {payload_len}-byte payload")
        offset = off + comp
        if with_data:
            raw = _frame(payload[off:offset], raw_len, what)
            if zlib.crc32(raw) != crc:
                raise BktError(f"{what}: CRC-32 is {zlib.crc32(raw):08x}, the file stores {crc:08x}")
            arrays[name] = np.frombuffer(raw, dtype=dtype).reshape(shape).copy()
    if offset != payload_len:
        raise BktError(f"the arrays' frames cover {offset} bytes of the {payload_len}-byte payload")
    return directory, arrays


def read_bkt(path):
    """(kind, metadata, {name: np.ndarray}) of a .bkt file, fully verified. Arrays are native
    numpy arrays of dtype float64, float32, uint32 or uint64 in C order."""
    with open(path, "rb") as f:
        directory, arrays = _parse(f.read())
    return directory["kind"], directory["metadata"], arrays


def read_bkt_directory(path):
    """The decoded JSON directory (kind, metadata, arrays with name/dtype/shape/attrs/…),
    without decompressing the arrays (header and directory are still verified)."""
    with open(path, "rb") as f:
        directory, _ = _parse(f.read(), with_data=False)
    return directory


def main(argv):
    args = [a for a in argv if a != "--no-data"]
    if not args or any(a.startswith("-") for a in args):
        print(__doc__.strip().splitlines()[0])
        print("usage: bkt.py [--no-data] FILE [FILE...]")
        return 2
    status = 0
    for path in args:
        try:
            directory = read_bkt_directory(path)
            arrays = None if "--no-data" in argv else read_bkt(path)[2]
        except (OSError, BktError) as e:
            print(f"{path}: ERROR: {e}")
            status = 1
            continue
        print(f"{path}: kind {directory['kind']!r}, {len(directory['arrays'])} arrays")
        print(f"  metadata: {json.dumps(directory['metadata'], ensure_ascii=False)[:400]}")
        for e in directory["arrays"]:
            line = f"  {e['name']}  {e['dtype']}{list(e['shape'])}"
            if e.get("attrs"):
                line += "  " + " ".join(f"{k}={v}" for k, v in e["attrs"].items())
            a = None if arrays is None else arrays[e["name"]]
            if a is not None and a.size:
                line += f"  min {a.min().item()!r} max {a.max().item()!r}"
            print(line)
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
