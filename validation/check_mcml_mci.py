#!/usr/bin/env python3
"""`baker mc --mci-in` on stock MCML 2.0 input files against MCML 2.0's own run of them.

Builds MCML 2.0 (Wang, Jacques & Zheng; public C source) with gcc -O3 as
validation/bench_mcml.py does (same `build_mcml`: a clone of the public repository by default,
or `--mcml-src` a local clone or checkout), runs it and `baker mc --mci-in` on the stock
samples committed under tests/stacks/mcml2/ (sample1.mci: two runs; sample2.mci: three layers;
photon counts as shipped), reads MCML's .mco RAT block, and checks for every run

    |Rd_baker − Rd_mcml| ≤ 3·sqrt(SE_baker² + SE_mcml²)   and the same for A (absorbed),

where both SEs are the standard error of a mean over per-photon weights w_i (the weight a
photon leaves as diffuse reflectance, or deposits in all layers):
    SE = (1/N)·sqrt(Σw² − (Σw)²/N)                    (MCML 2.0, mcmlio.c ScaleRdTd, ScaleA)
    SE = sqrt((Σw²/N − (Σw/N)²)/(N − 1))              (baker, stats::Sums::se)
the same up to N/(N − 1). Needs git, gcc and network access or a local clone, so CI does not
run it; baker/tests/cli.rs checks the same inputs against MCML numbers recorded in
tests/stacks/mcml2/README.md.

    python3 validation/check_mcml_mci.py --baker target/release/baker [--mcml-src PATH]
"""

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_mcml import MCML_GIT, build_mcml, parse_mco  # noqa: E402

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
SAMPLES = {
    "sample1.mci": ["sample1a.mco", "sample1b.mco"],
    "sample2.mci": ["sample2.mco"],
}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baker", required=True)
    ap.add_argument("--mcml-src", default=MCML_GIT, help="git URL or local clone of MCML")
    ap.add_argument("--mcml-rng", choices=["ran3", "splitmix64"], default="ran3")
    ap.add_argument("--seed", type=int, default=1, help="baker's seed")
    a = ap.parse_args()
    baker = os.path.abspath(a.baker)
    failures, rows = [], []
    with tempfile.TemporaryDirectory() as work:
        exe, commit = build_mcml(a.mcml_src, work, a.mcml_rng)
        for mci, outs in SAMPLES.items():
            shutil.copy(os.path.join(ROOT, "tests", "stacks", "mcml2", mci), work)
            subprocess.run([exe, mci], cwd=work, check=True, stdout=subprocess.DEVNULL)
            cmd = [baker, "mc", "--mci-in", mci, "-o", "baker", "--json", "-q"]
            p = subprocess.run(cmd + ["--seed", str(a.seed)], cwd=work, capture_output=True,
                               text=True)
            if p.returncode != 0:
                sys.exit(f"baker failed ({p.returncode}):\n{p.stderr[-2000:]}")
            results = [json.loads(line) for line in p.stdout.splitlines() if line.strip()]
            if len(results) != len(outs):
                sys.exit(f"{mci}: baker printed {len(results)} results for {len(outs)} runs")
            for out, b in zip(outs, results):
                if not os.path.isfile(os.path.join(work, "baker", out)):
                    failures.append(f"{mci}: baker wrote no baker/{out}")
                m = parse_mco(os.path.join(work, out))
                for key, xb, sb in [
                    ("Rd", b["rd"], b["rd_se"]),
                    ("A", b["absorbed_total"], b["absorbed_total_se"]),
                ]:
                    xm, sm = m[key]
                    s = math.hypot(sb, sm)
                    z = (xb - xm) / s if s > 0 else 0.0
                    rows.append((out, key, xb, sb, xm, sm, z))
                    if abs(z) > 3:
                        failures.append(f"{out} {key}: baker {xb:.6f} ± {sb:.6f}, MCML "
                                        f"{xm:.6f} ± {sm:.6f}, z = {z:+.2f}")
    print(f"MCML 2.0 ({commit[:10]}, {a.mcml_rng}) vs baker mc --mci-in (seed {a.seed})")
    print(f"{'run':<14}{'':4}{'baker':>10}{'SE':>10}{'MCML':>10}{'SE':>10}{'z':>7}")
    for out, key, xb, sb, xm, sm, z in rows:
        print(f"{out:<14}{key:<4}{xb:>10.6f}{sb:>10.6f}{xm:>10.6f}{sm:>10.6f}{z:>+7.2f}")
    if failures:
        print("\nFAIL:\n  " + "\n  ".join(failures))
        sys.exit(1)
    print("\nOK: every Rd and A within 3 combined standard errors")


if __name__ == "__main__":
    main()
