#!/usr/bin/env python3
"""`baker mc`'s radial diffuse reflectance Rd(r) against two independent references.

    python3 validation/check_rd_r.py --baker target/release/baker
        [--photons 4000000] [--seed 1] [--walk-photons 1000000] [--only a|b]

(a) MCML 2.0 (Wang, Jacques & Zheng, "MCML — Monte Carlo modeling of light transport in
    multi-layered tissues", Comput. Methods Programs Biomed. 47, 131–146 (1995)): the fixture
    tests/stacks/mcml_rd_r/ (rd_r.csv, totals.csv, stack.json; made by
    validation/make_mcml_rd_fixture.py from 8 × 2,000,000 photons of MCML 2.0 with SplitMix64)
    against `baker mc tests/stacks/mcml_rd_r/stack.json --photons P --seed S --json`, whose
    rd_r_per_mm2 is merged into the fixture's bins by the fixture's own `merge` (area-weighted
    mean over 0.01 mm annuli). P defaults to 4,000,000: a quarter of the fixture's photons, so
    that most of the variance of each difference is baker's per-photon SE and the fixture's SE
    (from the spread of 8 runs, 7 degrees of freedom) matters little (the Welch–Satterthwaite
    degrees of freedom of each z are printed; the normal threshold assumes they are large).

(b) A Monte Carlo walk written here from scratch in vectorised numpy (no code from the Rust
    engine or MCML): one homogeneous slab (n = 1.4 in air above and below, μa 0.2 /mm, μs 10 /mm,
    Henyey–Greenstein g = 0.8, 2 mm thick), pencil beam at normal incidence, specular Rsp
    removed at entry, exponential free paths (a path that reaches a boundary stops there and a
    fresh one is drawn after it, as free paths are memoryless in one medium), unpolarised
    Fresnel reflection (s and p amplitudes, total internal reflection) chosen probabilistically,
    ANALOG absorption (a packet ends at an interaction with chance μa/μt; no weights, no
    roulette), HG directions turned with Duff et al.'s orthonormal basis (JCGT 6(1), 2017),
    numpy's PCG64 generator. Scattered packets leaving the top are binned at their exit point
    r = hypot(x, y) into 0.01 mm annuli, divided by the annulus area π(r_hi² − r_lo²), then
    merged like (a). The same slab goes through `baker mc` (a temporary stack JSON). Bins where
    the walk scored fewer than 100 packets are skipped (the normal approximation needs counts).

Each comparison: z = (baker − reference) / sqrt(se_baker² + se_ref²) per bin, plus the totals
(Rd; in (b) also Tt); it passes if max |z| is below the Šidák threshold for that many tests at a
family-wise alpha of 0.001 (two-sided): Φ⁻¹(1 − (1 − (1 − 0.001)^(1/m))/2), 4.20 for m = 37.
baker's SE of a merged bin treats its annuli as uncorrelated (slightly conservative: one
packet exits once, so annulus sums are negatively correlated). Exit status 1 on failure.

Runtime on this project's busy 2-core machine: (a) ~45 s (baker, 4,000,000 photons, 2 threads),
(b) ~10 s (numpy walk ~8 s, baker ~2 s).
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

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import make_mcml_rd_fixture as fx  # noqa: E402

FIXTURE = os.path.join(os.path.dirname(HERE), "tests", "stacks", "mcml_rd_r")
ALPHA = 1e-3
MIN_COUNT = 100

# (b)'s slab.
SLAB = {"eta": 1.4, "n_above": 1.0, "n_below": 1.0, "d_mm": 2.0,
        "mua": 0.2, "mus": 10.0, "g": 0.8, "dr_mm": 0.01, "nr": 500}


def sidak_threshold(m, alpha=ALPHA):
    """|z| threshold of m two-sided normal tests at family-wise alpha (Šidák)."""
    per_test = 1.0 - (1.0 - alpha) ** (1.0 / m)
    lo, hi = 0.0, 40.0
    for _ in range(200):  # erfc(z/√2) = per_test, by bisection
        mid = 0.5 * (lo + hi)
        if math.erfc(mid / math.sqrt(2.0)) > per_test:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def run_baker(baker, stack_path, photons, seed, threads):
    cmd = [baker, "mc", stack_path, "--photons", str(photons), "--seed", str(seed),
           "--json", "--quiet"]
    if threads:
        cmd += ["--threads", str(threads)]
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr[-2000:]}")
    print(f"  {' '.join(cmd)}: {time.time() - t0:.1f} s", flush=True)
    return json.loads(p.stdout)


def baker_bins(b, dr_mm, edges_idx):
    r = b["r_mm"]
    if abs(r[0] - 0.5 * dr_mm) > 1e-9 or abs(r[1] - r[0] - dr_mm) > 1e-9:
        sys.exit(f"baker's grid (r_mm {r[:2]}) is not dr = {dr_mm} mm")
    if len(r) < edges_idx[-1]:
        sys.exit(f"baker's grid has {len(r)} annuli, fewer than the bins need")
    return (fx.merge(b["rd_r_per_mm2"], dr_mm, edges_idx),
            fx.merge_se(b["rd_r_per_mm2_se"], dr_mm, edges_idx))


def compare(title, names, ours, se_ours, ref, se_ref, dof_ref=None):
    """Prints one line per test; returns (max |z|, threshold, passed)."""
    m = len(names)
    thr = sidak_threshold(m)
    print(f"\n{title}")
    print(f"{'test':<22}{'baker':>13}{'reference':>13}{'diff %':>9}{'z':>8}" +
          ("   dof" if dof_ref else ""))
    worst, worst_name = 0.0, ""
    for k in range(m):
        s = math.hypot(se_ours[k], se_ref[k])
        z = (ours[k] - ref[k]) / s if s > 0 else 0.0
        rel = (ours[k] / ref[k] - 1.0) * 100 if ref[k] else float("nan")
        line = f"{names[k]:<22}{ours[k]:13.6g}{ref[k]:13.6g}{rel:9.2f}{z:8.2f}"
        if dof_ref:
            # Welch–Satterthwaite degrees of freedom of z (baker's SE taken as exact).
            nu = dof_ref * (s ** 4) / (se_ref[k] ** 4) if se_ref[k] > 0 else float("inf")
            line += f" {min(nu, 9999):5.0f}"
        if abs(z) > thr:
            line += "   <-- beyond threshold"
        print(line)
        if abs(z) > worst:
            worst, worst_name = abs(z), names[k]
    ok = worst < thr
    print(f"max |z| = {worst:.2f} ({worst_name}); Šidák threshold for {m} tests at family-wise "
          f"alpha {ALPHA}: {thr:.2f} -> {'PASS' if ok else 'FAIL'}")
    return worst, thr, ok


def bin_names(edges_idx, dr_mm):
    return [f"Rd {a * dr_mm:.2f}-{b * dr_mm:.2f} mm" for a, b in zip(edges_idx[:-1], edges_idx[1:])]


def part_a(a):
    print("(a) baker mc against MCML 2.0 (tests/stacks/mcml_rd_r)")
    stack_path = os.path.join(FIXTURE, "stack.json")
    dr_mm = json.load(open(stack_path))["grid"]["dr_mm"]
    header, rows = fx.read_fixture(os.path.join(FIXTURE, "rd_r.csv"))
    edges_idx = [round(rows[0][0] / dr_mm)] + [round(r[1] / dr_mm) for r in rows]
    for (lo, hi, *_), i0, i1 in zip(rows, edges_idx[:-1], edges_idx[1:]):
        if abs(lo - i0 * dr_mm) > 1e-9 or abs(hi - i1 * dr_mm) > 1e-9:
            sys.exit(f"fixture bin {lo}-{hi} mm is not on the {dr_mm} mm grid")
    k_runs = next((int(h.split("K = ")[1].split()[0]) for h in header if "K = " in h), 8)
    totals = fx.read_totals(os.path.join(FIXTURE, "totals.csv"))
    b = run_baker(a.baker, stack_path, a.photons, a.seed, a.threads)
    ours, se_ours = baker_bins(b, dr_mm, edges_idx)
    names = bin_names(edges_idx, dr_mm) + ["Rd total"]
    ours += [b["rd"]]
    se_ours += [b["rd_se"]]
    ref = [r[2] for r in rows] + [totals["Rd"][0]]
    se_ref = [r[3] for r in rows] + [totals["Rd"][1]]
    return compare(f"baker ({a.photons} photons, seed {a.seed}) vs MCML 2.0 "
                   f"({k_runs} runs; SE from their spread, {k_runs - 1} dof)",
                   names, ours, se_ours, ref, se_ref, dof_ref=k_runs - 1)


# --- (b): an independent numpy walk --------------------------------------------------------

def fresnel_unpolarised(n1, n2, cos_i):
    """Reflectance for light in medium n1 meeting n2 at incidence cosine cos_i (array)."""
    if n1 == n2:
        return np.zeros_like(cos_i)
    sin_t2 = (n1 / n2) ** 2 * (1.0 - cos_i * cos_i)
    tir = sin_t2 >= 1.0
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin_t2))
    rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)
    rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t)
    return np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp))


def hg_turn(ux, uy, uz, g, rng):
    """New directions: HG polar angle about the old direction, uniform azimuth."""
    n = ux.size
    u = rng.random(n)
    if g == 0.0:
        ct = 2.0 * u - 1.0
    else:
        f = (1.0 - g * g) / (1.0 - g + 2.0 * g * u)
        ct = np.clip((1.0 + g * g - f * f) / (2.0 * g), -1.0, 1.0)
    st = np.sqrt(np.maximum(0.0, 1.0 - ct * ct))
    phi = 2.0 * np.pi * rng.random(n)
    cp, sp = np.cos(phi), np.sin(phi)
    # Orthonormal basis (t1, t2, u) about u (Duff et al. 2017, branchless).
    s = np.where(uz >= 0.0, 1.0, -1.0)
    aa = -1.0 / (s + uz)
    bb = ux * uy * aa
    t1x, t1y, t1z = 1.0 + s * ux * ux * aa, s * bb, -s * ux
    t2x, t2y, t2z = bb, s + uy * uy * aa, -uy
    nx = st * (cp * t1x + sp * t2x) + ct * ux
    ny = st * (cp * t1y + sp * t2y) + ct * uy
    nz = st * (cp * t1z + sp * t2z) + ct * uz
    norm = np.sqrt(nx * nx + ny * ny + nz * nz)
    return nx / norm, ny / norm, nz / norm


def numpy_walk(photons, slab, seed, chunk=250_000):
    """Analog walk in one slab. Returns per-annulus counts of scattered top exits (nr + 1: the
    last is beyond the grid), and counts of unscattered top exits, bottom exits, absorptions."""
    n_t, n_up, n_dn, d = slab["eta"], slab["n_above"], slab["n_below"], slab["d_mm"]
    mua, mus, g = slab["mua"], slab["mus"], slab["g"]
    mut = mua + mus
    dr, nr = slab["dr_mm"], slab["nr"]
    rng = np.random.default_rng(seed)
    hist = np.zeros(nr + 1, dtype=np.int64)
    top_unscattered = bottom = absorbed = 0
    done = 0
    while done < photons:
        n = min(chunk, photons - done)
        done += n
        x = np.zeros(n)
        y = np.zeros(n)
        z = np.zeros(n)
        ux = np.zeros(n)
        uy = np.zeros(n)
        uz = np.ones(n)
        scat = np.zeros(n, dtype=bool)
        while x.size:
            step = -np.log1p(-rng.random(x.size)) / mut
            with np.errstate(divide="ignore", invalid="ignore"):
                dist = np.where(uz < 0.0, -z / uz, np.where(uz > 0.0, (d - z) / uz, np.inf))
            hit = step >= dist
            t = np.where(hit, dist, step)
            x = x + t * ux
            y = y + t * uy
            z = z + t * uz
            u = rng.random(x.size)
            keep = np.ones(x.size, dtype=bool)
            # Boundaries: Fresnel decides reflection (mirror uz) or escape.
            up = hit & (uz < 0.0)
            dn = hit & (uz > 0.0)
            z[up] = 0.0
            z[dn] = d
            r_fres = np.zeros(x.size)
            r_fres[up] = fresnel_unpolarised(n_t, n_up, -uz[up])
            r_fres[dn] = fresnel_unpolarised(n_t, n_dn, uz[dn])
            refl = hit & (u < r_fres)
            esc = hit & ~refl
            uz = np.where(refl, -uz, uz)
            esc_up = esc & up
            top_unscattered += int(np.count_nonzero(esc_up & ~scat))
            sc_up = esc_up & scat
            if sc_up.any():
                ir = np.minimum((np.hypot(x[sc_up], y[sc_up]) / dr).astype(np.int64), nr)
                hist += np.bincount(ir, minlength=nr + 1)
            bottom += int(np.count_nonzero(esc & dn))
            keep &= ~esc
            # Interactions: absorbed with chance μa/μt, else scattered.
            inter = ~hit
            absb = inter & (u < mua / mut)
            absorbed += int(np.count_nonzero(absb))
            keep &= ~absb
            sc = inter & ~absb
            if sc.any():
                ux[sc], uy[sc], uz[sc] = hg_turn(ux[sc], uy[sc], uz[sc], g, rng)
                scat |= sc
            x, y, z, ux, uy, uz, scat = (v[keep] for v in (x, y, z, ux, uy, uz, scat))
    return hist, top_unscattered, bottom, absorbed


def part_b(a):
    s = SLAB
    print(f"\n(b) baker mc against an independent numpy walk: slab n {s['eta']} "
          f"(above {s['n_above']}, below {s['n_below']}), d {s['d_mm']} mm, mua {s['mua']} /mm, "
          f"mus {s['mus']} /mm, g {s['g']}")
    t0 = time.time()
    hist, top_unsc, bottom, absorbed = numpy_walk(a.walk_photons, s, a.seed)
    n = a.walk_photons
    rsp = ((s["n_above"] - s["eta"]) / (s["n_above"] + s["eta"])) ** 2
    w0 = 1.0 - rsp  # every packet carries 1 − Rsp (analog: weight never changes)
    print(f"  numpy walk, {n} packets (PCG64 seed {a.seed}): {time.time() - t0:.1f} s; "
          f"Rsp {rsp:.6f}, unscattered top exits {top_unsc}, absorbed {absorbed / n:.4f}",
          flush=True)
    if int(hist.sum()) + top_unsc + bottom + absorbed != n:
        sys.exit("numpy walk lost packets")
    dr, nr = s["dr_mm"], s["nr"]
    ann = np.arange(nr)
    area = np.pi * dr * dr * (2 * ann + 1)
    p = hist[:nr] / n
    walk_r = w0 * p / area
    walk_r_se = w0 * np.sqrt(p * (1.0 - p) / n) / area
    edges_idx = fx.EDGES_IDX
    walk_bins = fx.merge(walk_r.tolist(), dr, edges_idx)
    walk_bins_se = fx.merge_se(walk_r_se.tolist(), dr, edges_idx)
    counts = [int(hist[i0:i1].sum()) for i0, i1 in zip(edges_idx[:-1], edges_idx[1:])]
    p_rd = hist.sum() / n
    p_tt = bottom / n
    stack = {"n_above": s["n_above"], "n_below": s["n_below"],
             "layers": [{"name": "slab", "d_mm": s["d_mm"], "eta": s["eta"],
                         "mua_per_mm": s["mua"], "mus_per_mm": s["mus"], "g": s["g"]}],
             "grid": {"dr_mm": dr, "nr": nr}}
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "slab.json")
        with open(path, "w") as f:
            json.dump(stack, f)
        b = run_baker(a.baker, path, a.walk_baker_photons, a.seed, a.threads)
    ours, se_ours = baker_bins(b, dr, edges_idx)
    keep = [k for k, c in enumerate(counts) if c >= MIN_COUNT]
    skipped = [k for k in range(len(counts)) if k not in keep]
    if skipped:
        print(f"  skipped (fewer than {MIN_COUNT} walk packets): " +
              ", ".join(bin_names(edges_idx, dr)[k] for k in skipped))
    names = [bin_names(edges_idx, dr)[k] for k in keep] + ["Rd total", "Tt total"]
    ours_k = [ours[k] for k in keep] + [b["rd"], b["tt"]]
    se_ours_k = [se_ours[k] for k in keep] + [b["rd_se"], b["tt_se"]]
    ref = [walk_bins[k] for k in keep] + [w0 * p_rd, w0 * p_tt]
    se_ref = [walk_bins_se[k] for k in keep] + [w0 * math.sqrt(p_rd * (1 - p_rd) / n),
                                                w0 * math.sqrt(p_tt * (1 - p_tt) / n)]
    return compare(f"baker ({a.walk_baker_photons} photons) vs numpy walk ({n} packets)",
                   names, ours_k, se_ours_k, ref, se_ref)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baker", required=True, help="path of the baker binary")
    ap.add_argument("--photons", type=int, default=4_000_000, help="baker photons for (a)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--threads", type=int, default=0, help="baker --threads (default: all)")
    ap.add_argument("--walk-photons", type=int, default=1_000_000, help="numpy packets for (b)")
    ap.add_argument("--walk-baker-photons", type=int, default=1_000_000,
                    help="baker photons for (b)")
    ap.add_argument("--only", choices=["a", "b"], help="run one comparison only")
    a = ap.parse_args()
    a.baker = os.path.abspath(a.baker)
    results = {}
    if a.only in (None, "a"):
        results["a (MCML 2.0)"] = part_a(a)
    if a.only in (None, "b"):
        results["b (numpy walk)"] = part_b(a)
    print("\nverdict:")
    for k, (worst, thr, ok) in results.items():
        print(f"  {k}: max |z| {worst:.2f} < {thr:.2f}? {'PASS' if ok else 'FAIL'}")
    if not all(ok for *_, ok in results.values()):
        print("FAIL: baker's Rd(r) differs from a reference beyond noise")
        sys.exit(1)
    print("PASS")


if __name__ == "__main__":
    main()
