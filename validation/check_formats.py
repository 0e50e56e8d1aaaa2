#!/usr/bin/env python3
"""Three readers of the baker's tables must agree bit for bit, and the C API must give the
Python module's answers.

1. Bakes a tiny fiber spec (polyester, a silk sweep: 10 deg bins, 2048 photons per direction)
   and a tiny skin spec (tests/specs/profiles_small.yaml, --photons 20000) into a temporary
   directory; `--profiles FILE` and `--bcsdf FILE` add existing tables (e.g. the Fitzpatrick
   database) to what is checked.
2. Reads every .bkt and .bcsdf with the independent numpy reader (validation/read_native.py,
   written from formats/FORMAT.md), with the Python module `baker_formats` (the Rust reader,
   formats/python) and, for the HDF5 files, with h5py, and asserts identical dtypes, shapes
   and bytes, identical metadata, attached dimension scales and `units` attributes; it also
   recomputes BCSDF lookups (wi_map, flips, bins) from FORMAT.md and compares them with the
   Rust `eval`, `albedo` and `area_um`.
3. Builds libbaker_formats (cargo build --release -p baker-formats-capi) and
   validation/c/check_formats.c with the system C compiler, runs it, and replays every query
   it printed through the Python module: the answers must be equal (they come from the same
   Rust code), and its error checks must have passed.

Needs: pip install -r validation/requirements.txt && pip install ./formats/python
Usage: python3 validation/check_formats.py --baker target/release/baker \
           [--profiles out/fitzpatrick/profiles.bkt] [--bcsdf FILE.bcsdf] [--cc cc] [--no-c]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import read_native  # noqa: E402

try:
    import baker_formats as bf
except ImportError as e:  # pragma: no cover - set-up error
    sys.exit(f"check_formats: cannot import baker_formats ({e}); run `pip install ./formats/python`")

ROOT = Path(__file__).resolve().parents[1]
FIBER_SPEC = """version: 1
bake: {resolution_deg: 10, photons_per_direction: 2048, seed: 3, precision: f16, keep_bits: 8}
fibers:
  - {name: polyester, type: polyester, section: {shape: circle}, dye: disperse_red_1, depth_of_shade_percent: 1.0}
  - {name: silk, type: silk, section: {shape: silk}, seed: 1, sections: 2,
     sweep: {dyes: [reactive_blue_19], depth_of_shade_percent: [1], undyed: true}}
"""
# The same polyester stored as f32 with every mantissa bit: the other decoding path.
FIBER_SPEC_F32 = """version: 1
bake: {resolution_deg: 10, photons_per_direction: 2048, seed: 3, precision: f32, keep_bits: 23}
fibers:
  - {name: polyester_f32, type: polyester, section: {shape: circle}, dye: disperse_red_1, depth_of_shade_percent: 1.0}
"""
SKIN_SPEC = ROOT / "tests/specs/profiles_small.yaml"


class Checks:
    def __init__(self):
        self.failures = 0

    def __call__(self, ok, what, detail=""):
        ok = bool(ok)
        self.failures += not ok
        if not ok:
            print(f"FAIL {what}{': ' + detail if detail else ''}")
        return ok

    def section(self, what, before):
        print(f"{'ok  ' if self.failures == before else 'FAIL'} {what}")


def same(a, b):
    """Same dtype (byte order included), shape and bytes."""
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype.str == b.dtype.str and a.shape == b.shape and a.tobytes() == b.tobytes()


def describe(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return f"{a.dtype.str}{a.shape} vs {b.dtype.str}{b.shape}"


def check_bkt(path, ck):
    before = ck.failures
    kind, meta, native = read_native.read_bkt(path)
    rkind, rmeta, rust = bf.read_table(path)
    ck(kind == rkind, f"{path}: kind", f"{kind!r} vs {rkind!r}")
    ck(meta == rmeta, f"{path}: metadata differs between the numpy and Rust readers")
    ck(list(native) == list(rust), f"{path}: array names or order")
    for name in native:
        if name in rust:
            ck(same(native[name], rust[name]), f"{path}: {name}", describe(native[name], rust[name]))
    attrs = bf.read_table_attrs(path)
    n_arrays = len(native)
    if kind == "skin_profiles":
        check_profiles(path, meta, native, attrs, ck)
    h5 = Path(path).with_suffix(".h5")
    h5 = h5 if kind == "skin_profiles" and h5.exists() else None
    if h5:
        check_profiles_h5(h5, native, attrs, ck)
    ck.section(f"{path}: {kind}, {n_arrays} arrays: numpy reader == Rust reader"
               + (" == h5py" if h5 else ""), before)


def check_profiles(path, meta, native, attrs, ck):
    t = bf.ProfileTable(path)
    ck(t.entries == json.loads(meta["entries"]), f"{path}: ProfileTable.entries")
    ck(t.metadata == meta, f"{path}: ProfileTable.metadata")
    for e in t.entries:
        arrays = t.arrays(e)
        prefix = e + "/"
        mine = {k[len(prefix):]: v for k, v in native.items() if k.startswith(prefix)}
        ck(list(arrays) == list(mine), f"{path}: arrays({e}) names")
        for q, a in arrays.items():
            ck(q in mine and same(a, mine[q]), f"{path}: arrays({e})[{q}]")
        for q, a in t.array_attrs(e).items():
            ck(a == attrs[prefix + q], f"{path}: array_attrs({e})[{q}]")
        r, rgb = mine["r_mm"], mine["rd_rgb_per_mm2"]
        # At a bin centre the interpolation returns the bin's value exactly.
        ck(same(t.rd_rgb(e, r), rgb), f"{path}: rd_rgb({e}) at the bin centres")
        ck(same(t.rd_rgb(e, float(r[3])), rgb[3]), f"{path}: rd_rgb({e}) scalar")
        ck(same(t.albedo_rgb(e), mine["albedo_rgb"]), f"{path}: albedo_rgb({e})")
        g = t.gaussians(e)
        if "gaussians/variance_mm2" in mine:
            ck(same(g.variance_mm2, mine["gaussians/variance_mm2"]), f"{path}: gaussians({e}).variance_mm2")
            ck(same(g.weight_rgb, mine["gaussians/weight_rgb"]), f"{path}: gaussians({e}).weight_rgb")
            ck(same(g.error_rgb, mine["gaussians/error_rgb"]), f"{path}: gaussians({e}).error_rgb")
        attrs_e, group = t.attrs(e), meta["groups"][e]
        ck(sorted(attrs_e) == sorted(group), f"{path}: attrs({e}) keys")
        for k, v in group.items():
            ok = attrs_e.get(k) == v if isinstance(v, str) else float(attrs_e.get(k, "nan")) == v
            ck(ok, f"{path}: attrs({e})[{k}]", f"{attrs_e.get(k)!r} vs {v!r}")
    try:
        t.rd_rgb("no such entry", 1.0)
        ck(False, f"{path}: unknown entry raises ValueError")
    except ValueError:
        pass


def check_profiles_h5(h5, native, attrs, ck):
    with h5py.File(h5, "r") as f:
        for name, a in native.items():
            if not ck(name in f, f"{h5}: dataset {name} missing"):
                continue
            d = f[name]
            ck(same(d[()], a), f"{h5}: {name} differs from the .bkt", describe(d[()], a))
            units = d.attrs.get("units")
            units = units.decode() if isinstance(units, bytes) else units
            ck(units is not None, f"{h5}: {name} has no units attribute")
            ck(units == attrs[name].get("units"), f"{h5}: {name} units", f"{units!r} vs {attrs[name].get('units')!r}")
            q = name.rsplit("/", 1)[-1]
            if q.startswith("rd_") and d.ndim == 2:
                group = name.rsplit("/", 1)[0]
                want = ["r_mm"] if q.startswith("rd_rgb") else ["lambda_nm", "r_mm"]
                for i, s in enumerate(want):
                    scales = [x.name for x in d.dims[i].values()]
                    ck(scales == [f"/{group}/{s}"], f"{h5}: {name} dimension {i} scale", f"{scales}")


def bin_of(theta, phi, res_rad, nt, nph):
    """FORMAT.md's grid: θ rows from −90°, φ columns from −180°, φ wrapped."""
    it = min(int((theta + math.pi / 2) / res_rad), nt - 1)
    p = phi - 2 * math.pi * math.floor((phi + math.pi) / (2 * math.pi))
    return it, min(int((p + math.pi) / res_rad), nph - 1)


def angles(w):
    n = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    return math.asin(max(-1.0, min(1.0, w[2] / n))), math.atan2(w[1], w[0])


def check_bcsdf(path, ck, rng):
    before = ck.failures
    d, f = read_native.read_bcsdf(path)
    t = bf.BcsdfTable(path)
    rf = t.f_normalised()
    ck(same(f, rf), f"{path}: f_normalised, numpy vs Rust", describe(f, rf))
    rd = t.directory
    for k in ("wi_deg", "area_um"):
        ck(same(np.array(d[k], dtype="<f8"), rd[k].reshape(-1) if k == "area_um" else rd[k]), f"{path}: {k}")
    ck(same(np.array(d["wi_map"], dtype="<u4").reshape(d["n_theta"], d["n_phi"]), rd["wi_map"]), f"{path}: wi_map")
    for k in ("scale", "albedo", "albedo_se"):
        mine = np.array(d[k], dtype=np.float64).astype("<f4").reshape(rd[k].shape)
        ck(same(mine, rd[k]), f"{path}: {k}")
    for k in ("kind", "res_deg", "n_theta", "n_phi", "variants", "channels", "dtype", "keep_bits", "chunks", "metadata"):
        ck(d[k] == rd[k], f"{path}: directory[{k}]")
    axes = t.axes
    res = d["res_deg"]
    ck(same(axes["theta_i_deg"], np.array([w[0] for w in d["wi_deg"]])), f"{path}: axes theta_i_deg")

    # Lookups recomputed from FORMAT.md: wi_map, flags, relative azimuth, bins.
    nt, nph, nc = d["n_theta"], d["n_phi"], len(d["channels"])
    albedo = np.array(d["albedo"], dtype=np.float64).astype(np.float32).reshape(len(d["wi_deg"]), len(d["variants"]), nc)
    r = math.radians(res)
    for _ in range(200):
        wi = rng.normal(size=3)
        wo = rng.normal(size=3)
        v = int(rng.integers(len(d["variants"])))
        (ti, pi), (to, po) = angles(wi), angles(wo)
        it, jp = bin_of(ti, pi, r, nt, nph)
        m = d["wi_map"][it * nph + jp]
        s, flip_t, flip_p = m & (2**30 - 1), bool(m >> 31 & 1), bool(m >> 30 & 1)
        dp = po - pi
        b = bin_of(-to if flip_t else to, -dp if flip_p else dp, r, nt, nph)
        fhat = f[s, v, :, b[0], b[1]]
        ck(same(t.eval_normalised(wi, wo, v), fhat), f"{path}: eval_normalised at {wi}, {wo}")
        ck(same(t.albedo(wi, v), albedo[s, v]), f"{path}: albedo at {wi}")
        ck(same(t.eval(wi, wo, v), fhat * albedo[s, v]), f"{path}: eval at {wi}, {wo}")
        ck(t.area_um(wi) == d["area_um"][bin_of(0.0, pi, r, nt, nph)[1]], f"{path}: area_um at {wi}")
        ck(t.projected_area(wi) == t.area_um(wi) * math.cos(ti), f"{path}: projected_area at {wi}")

    h5 = Path(path).parent / f"{Path(path).parent.name}.h5"
    if h5.exists():
        with h5py.File(h5, "r") as hf:
            g = hf[Path(path).stem]
            ck(same(g["f_normalised"][()], f), f"{h5}: f_normalised vs .bcsdf")
            ck(same(g["albedo"][()], rd["albedo"]), f"{h5}: albedo")
            ck(same(g["albedo_se"][()], rd["albedo_se"]), f"{h5}: albedo_se")
            ck(same(g["area_um"][()], rd["area_um"]), f"{h5}: area_um")
            ck(same(g["wi_map"][()], rd["wi_map"]), f"{h5}: wi_map")
            for k in ("theta_i_deg", "phi_i_deg", "theta_o_deg", "dphi_deg", "phi_deg"):
                ck(same(g[k][()], axes[k]), f"{h5}: {k} vs the Python module's axes")
            labels = [[s.name.rsplit("/", 1)[-1] for s in g["f_normalised"].dims[i].values()] for i in range(5)]
            want = [["theta_i_deg", "phi_i_deg"], ["variant"], ["channel"], ["theta_o_deg"], ["dphi_deg"]]
            ck(labels == want, f"{h5}: f_normalised dimension scales", f"{labels}")
            for k, u in (("f_normalised", "sr^-1"), ("area_um", "um")):
                ck(g[k].attrs.get("units") == u, f"{h5}: {k} units", f"{g[k].attrs.get('units')!r}")
            no_units = [k for k in ("theta_i_deg", "phi_i_deg", "theta_o_deg", "dphi_deg", "phi_deg", "albedo")
                        if "units" not in g[k].attrs]
            if no_units:
                print(f"note {h5}/{g.name}: no `units` attribute on {', '.join(no_units)}")
    ck.section(f"{path}: f_normalised {f.shape}: numpy reader == Rust reader"
               + (" == h5py" if h5.exists() else "") + "; 200 lookups match FORMAT.md", before)


def check_rejects(path, tmp, ck):
    """Both readers refuse the same damaged copies of a file."""
    before = ck.failures
    good = Path(path).read_bytes()
    bcsdf = good[:8] == b"BAKERFIB"
    damaged = {
        "truncated by one byte": good[:-1],
        "one more byte": good + b"\0",
        "bad magic": b"NOTATABL" + good[8:],
        "version 2": good[:8] + b"\2" + good[9:],
        "non-zero flags": good[:12] + b"\1" + good[13:],
        "last payload byte flipped": good[:-1] + bytes([good[-1] ^ 0x41]),
        "directory byte flipped": good[:60] + bytes([good[60] ^ 0x41]) + good[61:],
    }
    for what, b in damaged.items():
        p = Path(tmp) / ("damaged.bcsdf" if bcsdf else "damaged.bkt")
        p.write_bytes(b)
        try:
            read_native.read_bcsdf(p) if bcsdf else read_native.read_bkt(p)
            ck(False, f"{path}: numpy reader accepts a copy with {what}")
        except (read_native.FormatError, ValueError, KeyError):
            pass
        try:
            bf.BcsdfTable(p).f_normalised() if bcsdf else bf.read_table(p)
            ck(False, f"{path}: Rust reader accepts a copy with {what}")
        except ValueError:
            pass
    for reader in (bf.read_table, bf.ProfileTable, bf.BcsdfTable):
        try:
            reader(Path(tmp) / "missing.bkt")
            ck(False, f"{reader.__name__} opens a missing file")
        except OSError as e:
            ck("missing.bkt" in str(e), f"{reader.__name__}: the OSError names the path", str(e))
    ck.section(f"{path}: both readers reject {len(damaged)} damaged copies; missing files raise OSError", before)


def eq(a, b):
    return np.array_equal(np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64), equal_nan=True)


def check_c(profiles, bcsdf, cc, tmp, ck):
    before = ck.failures
    subprocess.run(["cargo", "build", "--release", "--quiet", "-p", "baker-formats-capi"], cwd=ROOT, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    exe = Path(tmp) / "check_formats"
    subprocess.run([cc, "-O2", "-std=c99", "-Wall", f"-I{ROOT / 'formats/capi/include'}",
                    str(ROOT / "validation/c/check_formats.c"), str(target / "release/libbaker_formats.a"),
                    "-lpthread", "-ldl", "-lm", "-o", str(exe)], check=True)
    run = subprocess.run([str(exe), str(profiles), str(bcsdf), str(Path(tmp) / "scratch.bin")],
                         capture_output=True, text=True)
    sys.stderr.write(run.stderr)
    ck(run.returncode == 0, "C program exit status", str(run.returncode))
    out = json.loads(run.stdout)
    ck(out["failures"] == 0, "C program reported failures", str(out["failures"]))
    for e in out["errors"]:
        ck(e["ok"] and (e["code"] == 0) == (e["message"] == ""), f"C error check {e['what']}", json.dumps(e))
    ck(out["library_version"] == bf.__version__, "library versions", f"{out['library_version']} vs {bf.__version__}")

    t = bf.ProfileTable(profiles)
    ck([e["name"] for e in out["profiles"]["entries"]] == t.entries, "C entries")
    n = 0
    for e in out["profiles"]["entries"]:
        name = e["name"]
        ck(eq(e["albedo_rgb"], t.albedo_rgb(name)), f"C albedo_rgb({name})")
        g = t.gaussians(name)
        ck(eq(e["gaussians"]["variance_mm2"], g.variance_mm2), f"C gaussians({name}).variance_mm2")
        ck(eq(np.reshape(e["gaussians"]["weight_rgb"], (-1, 3)), g.weight_rgb), f"C gaussians({name}).weight_rgb")
        ck(eq(e["gaussians"]["error_rgb"], g.error_rgb), f"C gaussians({name}).error_rgb")
        for q in e["rd_rgb"]:
            ck(eq(q["rgb"], t.rd_rgb(name, q["r_mm"])), f"C rd_rgb({name}, {q['r_mm']})")
            n += 1
    b = bf.BcsdfTable(bcsdf)
    ck(out["bcsdf"]["variants"] == b.variants and out["bcsdf"]["channels"] == b.channels, "C variant/channel names")
    for q in out["bcsdf"]["queries"]:
        wi, v = q["wi"], q["variant"]
        ck(eq(q["albedo"], b.albedo(wi, v)), f"C albedo({wi}, {v})")
        ck(q["projected_area_um"] == b.projected_area(wi), f"C projected_area({wi})")
        ck(q["area_um"] == b.area_um(wi), f"C area_um({wi})")
        for x in q["eval"]:
            wo = x["wo"]
            ck(eq(x["f"], b.eval(wi, wo, v)), f"C eval({wi}, {wo}, {v})")
            ck(eq(x["f_normalised"], b.eval_normalised(wi, wo, v)), f"C eval_normalised({wi}, {wo}, {v})")
            ck(x["pdf"] == b.pdf(wi, wo, v), f"C pdf({wi}, {wo}, {v})")
            n += 3
        for s in q["samples"]:
            got = b.sample(wi, s["u1"], s["u2"], v)
            want = ([0.0, 0.0, 0.0], 0.0) if got is None else (list(got[0]), got[1])
            ck(s["wo"] == want[0] and s["pdf"] == want[1], f"C sample({wi}, {s['u1']}, {s['u2']}, {v})",
               f"{s} vs {want}")
            n += 1
    ck.section(f"C API ({profiles.parent.name}/{profiles.name}, {Path(bcsdf).parent.name}/{Path(bcsdf).name}): {n} queries equal "
               f"to the Python module's, {len(out['errors'])} error checks passed", before)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baker", required=True, help="the baker binary (target/release/baker)")
    ap.add_argument("--profiles", action="append", default=[], help="an existing profiles.bkt to check too")
    ap.add_argument("--bcsdf", action="append", default=[], help="an existing .bcsdf to check too")
    ap.add_argument("--cc", default=os.environ.get("CC", "cc"), help="C compiler (default: $CC or cc)")
    ap.add_argument("--no-c", action="store_true", help="skip building and running the C program")
    a = ap.parse_args()
    ck = Checks()
    rng = np.random.default_rng(7)
    with tempfile.TemporaryDirectory() as tmp:
        bake = [a.baker, "bake", "--quiet", "--out", tmp]
        for name, text in (("formats_fibers", FIBER_SPEC), ("formats_fibers_f32", FIBER_SPEC_F32)):
            spec = Path(tmp) / f"{name}.yaml"
            spec.write_text(text)
            subprocess.run(bake + [str(spec)], check=True)
        subprocess.run(bake + ["--photons", "20000", str(SKIN_SPEC)], check=True)
        baked = Path(tmp)
        bkts = sorted(baked.rglob("*.bkt")) + [Path(p) for p in a.profiles]
        bcsdfs = sorted(baked.rglob("*.bcsdf")) + [Path(p) for p in a.bcsdf]
        ck(bkts and bcsdfs, "the bakes wrote .bkt and .bcsdf tables")
        for p in bkts:
            check_bkt(p, ck)
        for p in bcsdfs:
            check_bcsdf(p, ck, rng)
        check_rejects(bkts[0], tmp, ck)
        check_rejects(bcsdfs[0], tmp, ck)
        if not a.no_c:
            profiles = [p for p in bkts if bf.read_table(p)[0] == "skin_profiles"]
            # The silk sweep has two variants (undyed and dyed): both paths of the sampler.
            silk = [p for p in bcsdfs if p.parent.name == "silk"] or bcsdfs
            for p in profiles:
                check_c(p, silk[-1], a.cc, tmp, ck)
    print(f"check_formats: {'all checks passed' if not ck.failures else f'{ck.failures} FAILED'}")
    sys.exit(1 if ck.failures else 0)


if __name__ == "__main__":
    main()
