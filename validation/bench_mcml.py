#!/usr/bin/env python3
"""`baker mc` against MCML 2.0 (Wang, Jacques & Zheng 1995; public C source) on one core.

Builds MCML 2.0 from its public source with gcc -O3, then runs it and `baker mc --threads 1`
on the same planar five-layer skin stack (Henyey–Greenstein g = 0.9, μs 14–58 /mm, 550 nm
optics of the default five-layer model at age 30, type II) with the same number of photons,
in interleaved pairs, and reports:

- photons/s of each per CPU second (user + system time of the child process, whole process:
  start-up, input, output included), median over the pairs, and their ratio;
- the answers: diffuse reflectance Rd, unscattered reflectance, transmittance, absorption per
  layer and Rd(r) in five radial bands, as z-scores between the two programs (each within 3 SE).

MCML is never shipped or committed: its source is cloned (default: the public GitHub
repository below) into a temporary directory. Needs git, gcc and network access (or a local
clone: `--mcml-src /path/to/MCML`), so CI does not run it; it is the benchmark of the skin
transport issue (validation/bench-runs/).

    python3 validation/bench_mcml.py --baker target/release/baker [--photons 300000] [--pairs 5]

`--mcml-rng splitmix64` builds MCML with SplitMix64 in place of its own generator (Knuth's
subtractive `ran3`), which at a few million photons biases MCML's Rd(r) by ~0.7 % (bench record
2026-12-02, second); use it to compare answers at high photon counts.
"""

import argparse
import glob
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import tempfile

MCML_GIT = "https://github.com/mhjlam/MCML"

# The stack (mm, per mm). Thicknesses are multiples of 0.02 mm so that an A_z grid of that
# step gives MCML's absorption per layer.
LAYERS = [
    ("sc", 0.02, 1.53, 0.6951, 57.559),
    ("le", 0.08, 1.34, 1.9297, 57.559),
    ("pd", 0.18, 1.395, 0.1688, 34.198),
    ("rd", 1.82, 1.39, 0.1013, 36.558),
    ("hy", 5.90, 1.44, 0.3933, 14.388),
]
G = 0.9
N_BELOW = 1.44
DR_MM, NR = 0.01, 500
DZ_MM = 0.02
BANDS_MM = [(0.0, 0.1), (0.1, 0.3), (0.3, 1.0), (1.0, 2.0), (2.0, 4.9)]


def stack_json():
    return {
        "n_above": 1.0,
        "n_below": N_BELOW,
        "layers": [
            {"name": n, "d_mm": d, "eta": eta, "mua_per_mm": mua, "mus_per_mm": mus, "g": G}
            for n, d, eta, mua, mus in LAYERS
        ],
        "grid": {"dr_mm": DR_MM, "nr": NR},
    }


def mci(photons, out):
    """MCML 2.0's input: cm and 1/cm."""
    depth_mm = sum(d for _, d, *_ in LAYERS)
    nz = round(depth_mm / DZ_MM)
    media = "\n".join(
        f"  {n} {eta} {mua * 10:.6g} {mus * 10:.6g} {G}" for n, _, eta, mua, mus in LAYERS
    )
    layers = "\n".join(f"  {n} {d / 10:.6g}" for n, d, *_ in LAYERS)
    return f"""mcmli2.0
  air 1.0 0 0 0
{media}
  below {N_BELOW} 0 0 0
end
{out} A
  air
{layers}
  below
end
pencil
0
{DZ_MM / 10:.6g} {DR_MM / 10:.6g} 0.1
{nz} {NR} 1 1
A_z Rd_r
{photons} 1:00
1E-4
1
end
"""


# MCML's generator (Knuth's subtractive lagged Fibonacci "ran3", mcmlgo.c) replaced by
# SplitMix64 (Steele, Lea & Flood 2014) for `--mcml-rng splitmix64`; nothing else changes.
SPLITMIX = """static unsigned long long sm_state = 0x9E3779B97F4A7C15ULL;
static double sm_next(void) {
    unsigned long long z = (sm_state += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    z ^= z >> 31;
    return ((z >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}
#define RandomNum sm_next()"""


def patch_rng(c_dir, work):
    """A copy of the MCML sources with SplitMix64 as its generator."""
    out = os.path.join(work, "mcml-splitmix")
    os.makedirs(out, exist_ok=True)
    for f in glob.glob(os.path.join(c_dir, "*")):
        text = open(f).read()
        if os.path.basename(f) == "mcmlgo.c":
            old = "#define RandomNum (double)RandomGen(1, 0, NULL)"
            if old not in text:
                sys.exit("mcmlgo.c: RandomNum macro not found; cannot replace the generator")
            text = text.replace(old, SPLITMIX)
        with open(os.path.join(out, os.path.basename(f)), "w") as g:
            g.write(text)
    return out


def build_mcml(src, work, rng="ran3"):
    """Compiles MCML 2.0 from `src` (a git URL, a git repository, or a checkout), with its own
    generator or (`rng="splitmix64"`) SplitMix64."""
    sub = os.path.join("2.0.0", "src", "mcml")
    if os.path.isdir(os.path.join(src, sub)):
        c_dir, commit = os.path.join(src, sub), "local checkout"
    else:
        clone = os.path.join(work, "MCML")
        remote = "://" in src
        cmd = ["git", "clone", "--quiet", "--no-checkout"]
        cmd += ["--depth", "1", "--filter=blob:none"] if remote else []
        subprocess.run([*cmd, src, clone], check=True)
        # Only the MCML 2.0 sources: the repository also holds large binary test data.
        subprocess.run(["git", "-C", clone, "checkout", "--quiet", "HEAD", "--", sub], check=True)
        c_dir = os.path.join(clone, sub)
        commit = subprocess.run(
            ["git", "-C", clone, "rev-parse", "HEAD"], capture_output=True, text=True, check=True
        ).stdout.strip()
    if rng == "splitmix64":
        c_dir = patch_rng(c_dir, work)
    sources = sorted(glob.glob(os.path.join(c_dir, "*.c")))
    if not sources:
        sys.exit(f"no MCML 2.0 sources under {c_dir}")
    exe = os.path.join(work, "mcml")
    subprocess.run(["gcc", "-O3", "-o", exe, *sources, "-lm"], check=True)
    return exe, commit


def cpu_seconds(cmd, cwd):
    """Runs `cmd`; returns (CPU seconds of the child, stdout)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit(f"{cmd[0]} failed ({p.returncode}):\n{p.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, p.stdout


def parse_mco(path):
    """RAT values with their SEs, A_z [1/cm] and Rd_r [1/cm²] of an MCML 2.0 .mco file."""
    lines = open(path).read().splitlines()
    out, i = {}, 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("RAT"):
            for row in lines[i + 2 : i + 8]:
                vals, tag = row.split("#")
                key = tag.split(":")[0].strip()
                nums = vals.split()
                out[key] = (float(nums[0]), float(nums[1]) if len(nums) > 1 else 0.0)
            i += 8
            continue
        for key in ("A_z", "Rd_r"):
            if line.startswith(key + " "):
                arr = []
                i += 1
                while i < len(lines) and lines[i].strip():
                    arr.extend(float(x) for x in lines[i].split())
                    i += 1
                out[key] = arr
        i += 1
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baker", required=True)
    ap.add_argument("--mcml-src", default=MCML_GIT, help="git URL or local clone of MCML")
    ap.add_argument("--photons", type=int, default=300_000)
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument(
        "--mcml-rng",
        choices=["ran3", "splitmix64"],
        default="ran3",
        help="MCML's own generator, or SplitMix64 in its place: at 3,000,000 photons ran3 "
        "biases Rd(r) by ~0.7 %% (bench record 2026-12-02, second)",
    )
    ap.add_argument("--json", help="write the figures here")
    a = ap.parse_args()
    baker = os.path.abspath(a.baker)
    with tempfile.TemporaryDirectory() as work:
        exe, commit = build_mcml(a.mcml_src, work, a.mcml_rng)
        with open(os.path.join(work, "run.mci"), "w") as f:
            f.write(mci(a.photons, "run.mco"))
        with open(os.path.join(work, "stack.json"), "w") as f:
            json.dump(stack_json(), f)
        t_mcml, t_baker, b = [], [], None
        for k in range(a.pairs):
            # Interleaved, alternating which goes first, so drifts of the machine hit both.
            order = ["mcml", "baker"] if k % 2 == 0 else ["baker", "mcml"]
            for who in order:
                if who == "mcml":
                    cpu, _ = cpu_seconds([exe, "run.mci"], work)
                    t_mcml.append(cpu)
                else:
                    cmd = [baker, "mc", "stack.json", "--threads", "1", "--json"]
                    cmd += ["--photons", str(a.photons), "--seed", str(k + 1)]
                    cpu, out = cpu_seconds(cmd, work)
                    t_baker.append(cpu)
                    b = json.loads(out)
            print(f"pair {k + 1}: MCML {t_mcml[-1]:.2f} s, baker {t_baker[-1]:.2f} s CPU", flush=True)
        m = parse_mco(os.path.join(work, "run.mco"))

    # Photons/s per CPU second and the ratio of medians.
    med_m, med_b = statistics.median(t_mcml), statistics.median(t_baker)
    ratio = med_m / med_b
    print(f"\nMCML 2.0 ({commit[:10]}, gcc -O3): median {med_m:.2f} s CPU, "
          f"{a.photons / med_m:,.0f} photons/s")
    print(f"baker mc --threads 1:      median {med_b:.2f} s CPU, "
          f"{a.photons / med_b:,.0f} photons/s, "
          f"{b['scattering_events'] / b['photons']:.1f} events/packet, "
          f"{b['scattering_events_per_s'] / 1e6:.2f} M events/s in transport")
    print(f"ratio (baker photons/s over MCML's): {ratio:.2f}x  "
          f"(ranges: MCML {min(t_mcml):.2f}-{max(t_mcml):.2f} s, "
          f"baker {min(t_baker):.2f}-{max(t_baker):.2f} s)")

    # Answers: z-scores. MCML reports SEs for its RAT totals; for A per layer and the Rd(r)
    # bands it reports none, and the two are the same estimator (implicit capture, roulette at
    # 1e-4 with chance 1/10, same photons), so its SE is taken equal to baker's.
    rows = []

    def z(name, xb, sb, xm, sm):
        s = math.hypot(sb, sm)
        zz = (xb - xm) / s if s > 0 else 0.0
        rows.append((name, xb, xm, zz))

    rd_m, rd_m_se = m["Rd"]
    z("Rd", b["rd"], b["rd_se"], rd_m, rd_m_se)
    rsp = m["Rsp"][0]
    z("unscattered R", b["rd_unscattered"], b["rd_unscattered_se"], m["Rb"][0] - rsp, m["Rb"][1])
    z("Tt", b["tt"], b["tt_se"], m["Td"][0], m["Td"][1])
    z("A total", sum(b["absorbed"]), math.sqrt(sum(s * s for s in b["absorbed_se"])), *m["A"])
    dz_cm = DZ_MM / 10
    a_z = m["A_z"]
    top = 0.0
    for (name, d, *_), xb, sb in zip(LAYERS, b["absorbed"], b["absorbed_se"]):
        lo, hi = round(top / DZ_MM), round((top + d) / DZ_MM)
        top += d
        xm = sum(a_z[lo:hi]) * dz_cm
        z(f"A {name}", xb, sb, xm, sb)
    r_edges = [k * DR_MM for k in range(NR + 1)]
    area = [math.pi * (r_edges[k + 1] ** 2 - r_edges[k] ** 2) for k in range(NR)]
    for lo, hi in BANDS_MM:
        ks = [k for k in range(NR - 1) if lo <= r_edges[k] and r_edges[k + 1] <= hi + 1e-12]
        xb = sum(b["rd_r_per_mm2"][k] * area[k] for k in ks)
        sb = math.sqrt(sum((b["rd_r_per_mm2_se"][k] * area[k]) ** 2 for k in ks))
        # MCML's Rd_r is per cm² on the same annuli.
        xm = sum(m["Rd_r"][k] / 100 * area[k] for k in ks)
        z(f"Rd {lo}-{hi} mm", xb, sb, xm, sb)
    print("\nquantity              baker        MCML        z")
    for name, xb, xm, zz in rows:
        print(f"{name:<18} {xb:11.6g} {xm:11.6g} {zz:8.2f}")
    worst = max(abs(r[3]) for r in rows)
    print(f"worst |z| = {worst:.2f} over {len(rows)} quantities")
    if a.json:
        with open(a.json, "w") as f:
            json.dump({"mcml_commit": commit, "photons": a.photons, "mcml_cpu_s": t_mcml,
                       "baker_cpu_s": t_baker, "ratio": ratio,
                       "z": {r[0]: r[3] for r in rows}}, f, indent=1)
    if worst > 3.0:
        sys.exit("answers differ by more than 3 SE")


if __name__ == "__main__":
    main()
