#!/usr/bin/env python3
"""Summarise cargo-mutants results (validation/mutants/run.sh writes them).

    python3 validation/mutants/summary.py target/mutants/*/mutants.out [--missed]

One line per results folder (module): mutants tested, caught, timed out, missed, unviable,
and the score = (caught + timeout) / (caught + timeout + missed), the share of viable mutants
the tests catch, with a 95 % Wilson interval (a sample of a module's mutants, e.g.
`--shard 0/16`, estimates the whole module's score). `--missed` lists the surviving mutants.

`--sizes skin=490,transport=1858,…` (each module's mutant count, `run.sh MODULE --list | wc -l`)
adds the stratified score over all those modules: each module's sampled score weighted by its
size, Σ Wₘ pₘ with Wₘ = Nₘ / ΣN, and a 95 % interval from Σ Wₘ² p̃ₘ(1 − p̃ₘ)/nₘ with the
Agresti–Coull p̃ = (k + 2)/(n + 4) (a module whose sample caught everything still has
uncertainty). The pooled "all" line weights modules by how many of their mutants were sampled.
"""

import json
import math
import sys
from pathlib import Path


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (max(0.0, c - h), min(1.0, c + h))


def main() -> int:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    show_missed = "--missed" in sys.argv
    sizes = {}
    for a in sys.argv[1:]:
        if a.startswith("--sizes="):
            for kv in a.split("=", 1)[1].split(","):
                k, v = kv.split("=")
                sizes[k] = int(v)
    per_module = {}
    if not args:
        print(__doc__)
        return 2
    tot = {"caught": 0, "timeout": 0, "missed": 0, "unviable": 0}
    print(f"{'module':<12} {'tested':>6} {'caught':>6} {'timeout':>7} {'missed':>6} {'unviable':>8} {'score':>7}  95 % interval")
    for d in args:
        p = Path(d) / "outcomes.json"
        if not p.exists():
            print(f"{d}: no outcomes.json")
            continue
        o = json.loads(p.read_text())
        name = Path(d).parent.name
        c, t, m, u = o["caught"], o["timeout"], o["missed"], o["unviable"]
        for k, v in zip(tot, (c, t, m, u)):
            tot[k] += v
        module = name.split("-")[-1]
        k0, n0 = per_module.get(module, (0, 0))
        per_module[module] = (k0 + c + t, n0 + c + t + m)
        viable = c + t + m
        lo, hi = wilson(c + t, viable)
        score = (c + t) / viable if viable else float("nan")
        print(f"{name:<12} {c + t + m + u:>6} {c:>6} {t:>7} {m:>6} {u:>8} {score:>7.1%}  [{lo:.1%}, {hi:.1%}]")
        if show_missed:
            for oc in o["outcomes"]:
                if oc["summary"] == "MissedMutant":
                    print("    missed:", oc["scenario"]["Mutant"]["name"])
    viable = tot["caught"] + tot["timeout"] + tot["missed"]
    lo, hi = wilson(tot["caught"] + tot["timeout"], viable)
    if viable:
        print(f"{'all':<12} {viable + tot['unviable']:>6} {tot['caught']:>6} {tot['timeout']:>7} {tot['missed']:>6} "
              f"{tot['unviable']:>8} {(tot['caught'] + tot['timeout']) / viable:>7.1%}  [{lo:.1%}, {hi:.1%}]")
    if sizes:
        missing = [m for m in sizes if m not in per_module or per_module[m][1] == 0]
        if missing:
            print(f"stratified: no sample for {', '.join(missing)}")
            return 1
        total = sum(sizes.values())
        est, var = 0.0, 0.0
        for m, size in sizes.items():
            k, n = per_module[m]
            w = size / total
            est += w * k / n
            pt = (k + 2) / (n + 4)
            var += w * w * pt * (1 - pt) / n
        h = 1.96 * math.sqrt(var)
        print(f"stratified over {len(sizes)} modules ({total} mutants): {est:.1%}  "
              f"[{max(0.0, est - h):.1%}, {min(1.0, est + h):.1%}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
