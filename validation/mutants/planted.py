#!/usr/bin/env python3
"""The bugs issue 22 names, planted one at a time: each must make `cargo test` fail.

    python3 validation/mutants/planted.py [NAME …] [--list]

For every planted bug: edit one line of the source (the edit is undone afterwards, also on
Ctrl-C), run the test targets that should catch it (`cargo test --profile mutants -p baker
--no-fail-fast TARGETS`: the same tests `cargo test --workspace` runs, fewer of them), and
report which tests failed. Exits 1 if any planted bug passes every test. Takes a few minutes
per bug on 2 cores (incremental builds of the `mutants` profile, Cargo.toml).
"""

import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# (name, file, original text, planted text, test targets)
PLANTED = [
    ("beckmann lobe width alpha^2 -> alpha", "baker/src/fiber/surface.rs",
     "let tan2 = -alpha * alpha * u1.ln();", "let tan2 = -alpha * u1.ln();", ["--lib"]),
    ("Beer-Lambert exp(-mu l) -> exp(-mu l / 2) in the bake's channels", "baker/src/fiber/sweep.rs",
     "c * (-m * l).exp()", "c * (-m * l / 2.0).exp()", ["--test", "fiber_references"]),
    ("splitting: leaving branches keep the whole weight", "baker/src/fiber/tracer.rs",
     "let kw = ray.w / split as f64;", "let kw = ray.w;", ["--test", "fiber_references"]),
    ("splitting: the staying branch always goes on (no roulette at m/split)", "baker/src/fiber/tracer.rs",
     "u() * split as f64 >= m as f64", "u() * split as f64 >= split as f64", ["--test", "fiber_references"]),
    ("symmetry: mirror line at half its angle", "baker/src/fiber/symmetry.rs",
     "(2.0 * a / res_deg).round() as i64", "(a / res_deg).round() as i64", ["--test", "fiber_references"]),
    ("symmetry: z-mirror without the theta_o flip", "baker/src/fiber/symmetry.rs",
     "next.push(((n_theta - 1 - it) * n_phi + jp, f ^ FLIP_THETA));",
     "next.push(((n_theta - 1 - it) * n_phi + jp, f));", ["--test", "fiber_references"]),
    ("junction scale 2 pi -> pi", "baker/src/skin/layers.rs",
     "let omega = 2.0 * std::f64::consts::PI / (p.dej_period_um * 1e-3);",
     "let omega = std::f64::consts::PI / (p.dej_period_um * 1e-3);", ["--lib"]),
    ("junction amplitude A -> A/2", "baker/src/skin/layers.rs",
     "amplitude_mm: dej_amplitude_um(p) * 1e-3,", "amplitude_mm: dej_amplitude_um(p) * 0.5e-3,", ["--lib"]),
    ("sRGB transfer exponent 1/2.4 -> 1/2.2", "baker/src/spectral/colour.rs",
     "1.055 * x.powf(1.0 / 2.4) - 0.055", "1.055 * x.powf(1.0 / 2.2) - 0.055", ["--lib"]),
    ("sRGB matrix rows R and G swapped", "baker/src/spectral/colour.rs",
     "    [3.2406, -1.5372, -0.4986],\n    [-0.9689, 1.8758, 0.0415],",
     "    [-0.9689, 1.8758, 0.0415],\n    [3.2406, -1.5372, -0.4986],", ["--lib"]),
    ("energy: absorption in a layer not scored", "baker/src/transport/engine.rs",
     "s.absorb(layer, dw, &self.rel());", "if layer != 1 { s.absorb(layer, dw, &self.rel()); }",
     ["--test", "transport"]),
    ("Rd(r): exit radius 10 % short", "baker/src/transport/engine.rs",
     "let ir = (e.radius_mm() / self.dr_mm) as usize;", "let ir = (0.9 * e.radius_mm() / self.dr_mm) as usize;",
     ["--test", "transport"]),
    ("Rd(r): annulus area 2(i+1) instead of 2i+1", "baker/src/transport/tally.rs",
     "std::f64::consts::PI * dr_mm * dr_mm * (2 * i + 1) as f64", "std::f64::consts::PI * dr_mm * dr_mm * (2 * i + 2) as f64",
     ["--test", "transport"]),
    ("Rd(r) of the bake: annulus areas of the radial bins", "baker/src/transport/radial.rs",
     ".map(|w| std::f64::consts::PI * (w[1] * w[1] - w[0] * w[0]))",
     ".map(|w| std::f64::consts::PI * (w[1] * w[1] - w[0] * w[0]) * 1.05)", ["--test", "transport"]),
    ("Burley s(A): perpendicular cubic term 7|A-0.8|^3 -> 7|A-0.8|^2", "baker/src/export/burley/conventions.rs",
     "1.85 - a + 7.0 * (a - 0.8).abs().powi(3)", "1.85 - a + 7.0 * (a - 0.8).abs().powi(2)", ["--lib"]),
    ("junction: a packet below J(x, y) ignores it when its step ends inside the planes", "baker/src/transport/engine.rs",
     "if layer == *ju || layer == ju + 1);", "if layer == *ju || layer == ju * 1);", ["--test", "transport"]),
    ("cache key ignores the code digest", "baker/src/pipeline/mod.rs",
     "        h.update(code);\n", "", ["--lib"]),
]


def run(names: list[str]) -> int:
    chosen = [p for p in PLANTED if not names or any(n in p[0] for n in names)]
    failures = 0
    rows = []
    for name, rel, old, new, targets in chosen:
        path = ROOT / rel
        text = path.read_text()
        if text.count(old) != 1:
            print(f"SKIP {name}: the original text occurs {text.count(old)} times in {rel}")
            failures += 1
            continue
        t0 = time.time()
        try:
            path.write_text(text.replace(old, new))
            p = subprocess.run(
                ["cargo", "test", "--profile", "mutants", "-p", "baker", "--no-fail-fast", *targets],
                cwd=ROOT, capture_output=True, text=True)
        finally:
            path.write_text(text)
        out = p.stdout + p.stderr
        failed = sorted(set(re.findall(r"^test (\S+) \.\.\. FAILED", out, re.M)))
        if "error[E" in out or "could not compile" in out:
            verdict = "unviable (does not compile)"
            failures += 1
        elif p.returncode != 0 and failed:
            verdict = "caught by " + ", ".join(failed)
        else:
            verdict = "NOT CAUGHT"
            failures += 1
        rows.append((name, verdict))
        print(f"{name}: {verdict} ({time.time() - t0:.0f} s)", flush=True)
    print()
    for name, verdict in rows:
        print(f"| {name} | {verdict} |")
    return 1 if failures else 0


if __name__ == "__main__":
    if "--list" in sys.argv:
        for p in PLANTED:
            print(p[0])
        sys.exit(0)
    sys.exit(run([a for a in sys.argv[1:] if not a.startswith("--")]))
