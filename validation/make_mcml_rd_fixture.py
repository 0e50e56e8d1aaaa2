#!/usr/bin/env python3
"""Generates tests/stacks/mcml_rd_r/: MCML 2.0's radial diffuse reflectance Rd(r) on the planar
five-layer skin stack, in ~36 radial bins with standard errors, as an independent reference for
`baker mc`'s Rd(r) tally (a wrong exit radius or annulus area shows up there; see
validation/check_rd_r.py, which reads it).

MCML 2.0 (Wang, Jacques & Zheng, Comput. Methods Programs Biomed. 47, 131 (1995); public C
source, github.com/mhjlam/MCML, 2.0.0/src/mcml) is built with gcc -O3 by
validation/bench_mcml.py's `build_mcml` with SplitMix64 in place of its own generator
(`--mcml-rng splitmix64` there): MCML's lagged-Fibonacci ran3 biases Rd(r) by ~0.7 % at a few
million photons (validation/bench-runs/2026-12-02-skin-speed-2core-second.md), so the
high-photon-count reference must not use it. MCML 2.0 always seeds ran3 with 1 and bench_mcml's
SplitMix64 starts from a fixed state; here one extra constructor (below) sets SplitMix64's
initial state to SplitMix64's own output for the integer in MCML_SPLITMIX_SEED, so that the K
runs (seeds 1..K) draw from far-apart, effectively independent parts of the 2^64 cycle. Nothing
else in MCML changes. The stack, the .mci input and the .mco parser are bench_mcml's (LAYERS,
`mci`, `parse_mco`, `stack_json`): dr = 0.01 mm, nr = 500.

    python3 validation/make_mcml_rd_fixture.py [--runs 8] [--photons 2000000] [--jobs 1]
        [--mcml-src https://github.com/mhjlam/MCML | /path/to/clone]

Needs gcc and MCML's source (a git URL, a local clone or mirror; MCML's source is used from a
temporary directory and never written into this repository). With the defaults it takes
about 8 to 10 minutes on one core.

Binning. MCML 2.0 scores the weight w of a *scattered* packet leaving the top into annulus
i = floor(r/dr) (r >= nr·dr goes to the last annulus, an overflow bin, not used here) and
writes Rd_r[i] = W_i / (N · 2π(i + 0.5)·dr²) (ScaleRdTd in mcmlio.c), per cm²; 2π(i + 0.5)dr²
= π((i+1)² − i²)dr² is the annulus' exact area A_i. A merged bin of annuli a..b−1 is the
area-weighted mean Rd = Σ Rd_r[i]·A_i / Σ A_i = (Σ W_i / N) / (π(r_hi² − r_lo²)), i.e. the
reflected power per unit area of the merged annulus. `merge` below does this; check_rd_r.py
applies the same function to `baker mc`'s rd_r_per_mm2.
"""

import argparse
import concurrent.futures
import datetime
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench_mcml as bm  # noqa: E402

ROOT = os.path.dirname(HERE)
OUT_DIR = os.path.join(ROOT, "tests", "stacks", "mcml_rd_r")

# Edges of the merged bins, as indices of MCML's 0.01 mm annuli: the first ten annuli as they
# are, then widths growing ~16 % per bin (round(10·49.9^(j/26))), up to annulus 499 (4.99 mm),
# the start of MCML's overflow annulus.
EDGES_IDX = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 14, 16, 18, 21, 25, 29, 33, 39, 45, 52, 61,
             71, 82, 95, 111, 129, 150, 174, 202, 235, 273, 318, 369, 429, 499]

# SplitMix64 seeding added to bench_mcml.SPLITMIX (its generator itself is unchanged).
SEED_ANCHOR = "static unsigned long long sm_state = 0x9E3779B97F4A7C15ULL;"
SEEDING = SEED_ANCHOR + """
__attribute__((constructor)) static void sm_seed_from_env(void) {
    const char *e = getenv("MCML_SPLITMIX_SEED");
    if (e) {
        unsigned long long z = strtoull(e, NULL, 10) + 0x9E3779B97F4A7C15ULL;
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
        sm_state = z ^ (z >> 31);
    }
}"""


def merge(rd_r_per_area, dr, edges_idx=EDGES_IDX):
    """Area-weighted means of per-area values over merged annuli: bin [a, b) of annulus indices
    gets Σ_{a<=i<b} x_i·A_i / Σ A_i with A_i = π(2i+1)dr² (any area unit; dr cancels)."""
    out = []
    for a, b in zip(edges_idx[:-1], edges_idx[1:]):
        num = sum(rd_r_per_area[i] * (2 * i + 1) for i in range(a, b))
        out.append(num / (b * b - a * a))
    return out


def merge_se(se_per_area, dr, edges_idx=EDGES_IDX):
    """SE of `merge` from per-annulus SEs, treating annuli as uncorrelated. For a per-photon
    tally a packet exits once, so two annuli's sums are slightly *negatively* correlated
    (−μ_i μ_j / N): this is a (negligibly) conservative bound."""
    out = []
    for a, b in zip(edges_idx[:-1], edges_idx[1:]):
        var = sum((se_per_area[i] * (2 * i + 1)) ** 2 for i in range(a, b))
        out.append(math.sqrt(var) / (b * b - a * a))
    return out


def read_fixture(path):
    """(header lines, [(r_lo, r_hi, rd, se)]) of rd_r.csv or totals.csv-like files."""
    header, rows = [], []
    for line in open(path):
        line = line.rstrip("\n")
        if line.startswith("#"):
            header.append(line)
        elif line.strip() and not line[0].isalpha():
            rows.append(tuple(float(v) for v in line.split(",")))
    return header, rows


def read_totals(path):
    out = {}
    for line in open(path):
        if line.startswith("#") or not line.strip() or line.startswith("quantity"):
            continue
        k, v, s = line.strip().split(",")
        out[k] = (float(v), float(s))
    return out


def run_one(exe, work, photons, seed):
    name = f"run{seed}"
    with open(os.path.join(work, name + ".mci"), "w") as f:
        f.write(bm.mci(photons, name + ".mco"))
    env = dict(os.environ, MCML_SPLITMIX_SEED=str(seed))
    t0 = time.time()
    p = subprocess.run([exe, name + ".mci"], cwd=work, env=env, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"MCML failed on seed {seed} ({p.returncode}):\n{p.stderr[-2000:]}")
    m = bm.parse_mco(os.path.join(work, name + ".mco"))
    if len(m.get("Rd_r", [])) != bm.NR:
        sys.exit(f"{name}.mco: expected {bm.NR} Rd_r values")
    return seed, m, time.time() - t0


def mean_se(xs):
    """Mean of K independent runs and its SE from their spread (K−1 degrees of freedom)."""
    return statistics.fmean(xs), statistics.stdev(xs) / math.sqrt(len(xs))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mcml-src", default=bm.MCML_GIT, help="git URL, clone or mirror of MCML")
    ap.add_argument("--runs", type=int, default=8, help="K independent MCML runs")
    ap.add_argument("--photons", type=int, default=2_000_000, help="N photons per run")
    ap.add_argument("--jobs", type=int, default=1, help="MCML runs at once (default 1 core)")
    ap.add_argument("--out", default=OUT_DIR)
    a = ap.parse_args()
    if a.runs < 2:
        sys.exit("--runs must be at least 2 (the SE comes from their spread)")
    if SEED_ANCHOR not in bm.SPLITMIX:
        sys.exit("bench_mcml.SPLITMIX changed: its state line is not where seeding expects it")
    bm.SPLITMIX = bm.SPLITMIX.replace(SEED_ANCHOR, SEEDING)

    t_start = time.time()
    with tempfile.TemporaryDirectory() as work:
        exe, commit = bm.build_mcml(a.mcml_src, work, "splitmix64")
        t_build = time.time() - t_start
        print(f"built MCML 2.0 ({commit}) with seeded SplitMix64 in {t_build:.1f} s", flush=True)
        runs = {}
        with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
            futs = [pool.submit(run_one, exe, work, a.photons, k) for k in range(1, a.runs + 1)]
            for fut in concurrent.futures.as_completed(futs):
                seed, m, dt = fut.result()
                runs[seed] = m
                print(f"seed {seed}: Rd {m['Rd'][0]:.6f} ± {m['Rd'][1]:.6f}  {dt:.1f} s",
                      flush=True)
    elapsed = time.time() - t_start
    seeds = sorted(runs)
    dr_mm = bm.DR_MM

    # Per run: merged bins in 1/mm² (MCML writes 1/cm²).
    per_run = [merge([v / 100.0 for v in runs[k]["Rd_r"]], dr_mm) for k in seeds]
    bins = [mean_se([pr[j] for pr in per_run]) for j in range(len(EDGES_IDX) - 1)]
    if len({tuple(pr) for pr in per_run}) != len(per_run):
        sys.exit("two runs gave identical Rd(r): the seeding did not take effect")

    # Totals: MCML's RAT Rd (diffuse, scattered light only), Td, A, and Rd(r) integrated over
    # annuli 0..498 (0 to 4.99 mm; MCML's last annulus is an overflow bin).
    def integral(m):
        return sum(m["Rd_r"][i] / 100.0 * math.pi * dr_mm**2 * (2 * i + 1)
                   for i in range(EDGES_IDX[-1]))

    totals = {
        "Rd": mean_se([runs[k]["Rd"][0] for k in seeds]),
        "Td": mean_se([runs[k]["Td"][0] for k in seeds]),
        "A": mean_se([runs[k]["A"][0] for k in seeds]),
        "Rd_r_integrated_0_4.99mm": mean_se([integral(runs[k]) for k in seeds]),
    }
    # MCML's own per-photon SE of Rd, pooled over the runs (a cross-check of the spread).
    rd_se_mcml = math.sqrt(sum(runs[k]["Rd"][1] ** 2 for k in seeds)) / len(seeds)

    os.makedirs(a.out, exist_ok=True)
    layers = "; ".join(f"{n} d={d} mm n={eta} mua={mua}/mm mus={mus}/mm"
                       for n, d, eta, mua, mus in bm.LAYERS)
    regen = (f"python3 validation/make_mcml_rd_fixture.py --runs {a.runs} --photons {a.photons}"
             f" [--mcml-src {bm.MCML_GIT} or a local clone]")
    common = [
        f"# stack: planar, pencil beam at normal incidence, n_above 1.0, n_below {bm.N_BELOW}, "
        f"Henyey-Greenstein g = {bm.G} in every layer; {layers} (validation/bench_mcml.py LAYERS;"
        " tests/stacks/mcml_rd_r/stack.json)",
        f"# MCML 2.0 (Wang, Jacques & Zheng 1995), github.com/mhjlam/MCML commit {commit}, "
        "2.0.0/src/mcml, gcc -O3; RandomNum replaced by SplitMix64 (validation/bench_mcml.py "
        "SPLITMIX), initial state = SplitMix64 output of the run's seed (MCML_SPLITMIX_SEED); "
        "roulette and all else as MCML 2.0",
        f"# K = {a.runs} runs (seeds {seeds[0]}..{seeds[-1]}), N = {a.photons} photons each "
        f"({a.runs * a.photons} in all); generated {datetime.date.today().isoformat()} in "
        f"{elapsed:.0f} s wall ({a.jobs} job(s) at once)",
        f"# regenerate: {regen}",
    ]
    with open(os.path.join(a.out, "rd_r.csv"), "w") as f:
        f.write("# what: radial diffuse reflectance Rd(r) of MCML 2.0 (scattered light leaving "
                "the top; unscattered light and the specular Rsp excluded), per unit area, in "
                f"{len(bins)} radial bins from 0 to {EDGES_IDX[-1] * dr_mm:.2f} mm\n")
        for line in common:
            f.write(line + "\n")
        f.write(f"# grid: MCML dr = {dr_mm} mm, nr = {bm.NR}; MCML writes Rd_r[i] = W_i / "
                "(N * 2*pi*(i+0.5)*dr^2) per cm^2 (mcmlio.c ScaleRdTd), 2*pi*(i+0.5)*dr^2 = "
                "pi*((i+1)^2 - i^2)*dr^2 being annulus i's exact area; annulus 499 (r >= 4.99 "
                "mm, MCML's overflow) is not used\n")
        f.write("# merge: rd over annuli a..b-1 = sum_i Rd_r[i]*(2i+1) / (b^2 - a^2) / 100, i.e. "
                "the area-weighted mean = (sum_i W_i / N) / (pi*(r_hi^2 - r_lo^2)) in 1/mm^2 "
                "(validation/make_mcml_rd_fixture.py merge)\n")
        f.write("# rd = mean of the K runs' merged values; rd_se = their sample standard "
                "deviation / sqrt(K) (K - 1 degrees of freedom)\n")
        f.write("# units: r in mm; rd and rd_se in 1/mm^2 (fraction of the incident power per "
                "mm^2)\n")
        f.write("r_lo_mm,r_hi_mm,rd_per_mm2,rd_se_per_mm2\n")
        for (lo, hi), (v, s) in zip(zip(EDGES_IDX[:-1], EDGES_IDX[1:]), bins):
            f.write(f"{lo * dr_mm:.2f},{hi * dr_mm:.2f},{v:.9g},{s:.6g}\n")
    with open(os.path.join(a.out, "totals.csv"), "w") as f:
        f.write("# what: MCML 2.0 totals of the same runs as rd_r.csv: Rd (diffuse reflectance, "
                "scattered light only, RAT block), Td (diffuse transmittance), A (absorbed), "
                "Rd_r_integrated_0_4.99mm (sum of W_i/N over annuli 0..498)\n")
        for line in common:
            f.write(line + "\n")
        f.write("# value = mean of the K runs; se = sample standard deviation / sqrt(K); MCML's "
                f"own per-photon SE of Rd pooled over the runs: {rd_se_mcml:.6g}\n")
        f.write("# units: fractions of the incident power\n")
        f.write("quantity,value,se\n")
        for k, (v, s) in totals.items():
            f.write(f"{k},{v:.9g},{s:.6g}\n")
    with open(os.path.join(a.out, "stack.json"), "w") as f:
        json.dump(bm.stack_json(), f, indent=2)
        f.write("\n")
    print(f"\nwrote {a.out}/rd_r.csv, totals.csv, stack.json in {elapsed:.0f} s")
    print(f"Rd = {totals['Rd'][0]:.6f} ± {totals['Rd'][1]:.6f} (spread), "
          f"± {rd_se_mcml:.6f} (MCML per-photon)")
    for (lo, hi), (v, s) in list(zip(zip(EDGES_IDX[:-1], EDGES_IDX[1:]), bins))[:12]:
        print(f"  {lo * dr_mm:.2f}-{hi * dr_mm:.2f} mm: {v:.6g} ± {s:.3g} /mm² ({s / v:.2%})")


if __name__ == "__main__":
    main()
