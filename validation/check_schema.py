#!/usr/bin/env python3
"""The spec JSON Schemas (specs/schema/*.schema.json, written by `baker schema skin|fiber`)
checked with tools independent of the baker: the `jsonschema` package (draft 2020-12) and
ruamel.yaml's pure-Python YAML 1.2 loader (the YAML version serde-saphyr reads; PyYAML reads
1.1, where `1e6` is text and `on` is true).

1. Both schemas are valid draft 2020-12 schemas.
2. Every shipped spec (specs/, tests/specs/, validation/specs/) starts with a
   `# yaml-language-server: $schema=…` line pointing at the schema of its kind, and
   validates against it.
3. Every file of the broken-spec corpus (tests/specs/broken/, tests/specs/bad/) fails: at
   YAML load or against the schema. The few errors a schema cannot express (a file that does
   not exist, names unique across a list, one value below another, a divisor of 180°, a dye
   defined elsewhere in the spec, a dye's summed peak extinction) are listed in NEEDS_BAKER;
   for those `baker validate` must exit 2. The script fails when that list is not exactly
   the files the schema accepts, so a schema that starts accepting a broken spec is caught.
   `baker validate` is run on every corpus file (exit 2 expected) for the table.
4. The schema is never stricter than the baker: every spec of the hostile corpus
   (tests/specs/hostile/) that `baker validate` accepts validates against its schema too, and
   so do the specs of EDGES, written the ways the baker accepts that a naive schema would
   refuse (each must pass `baker validate` first).

    python3 validation/check_schema.py --baker target/release/baker
"""
import argparse
import json
import subprocess
import sys
from pathlib import Path

import jsonschema
from ruamel.yaml import YAML

ROOT = Path(__file__).resolve().parent.parent
SCHEMAS = {k: ROOT / "specs" / "schema" / f"{k}.schema.json" for k in ("skin", "fiber")}
SHIPPED = ["specs", "tests/specs", "validation/specs"]
CORPUS = ["tests/specs/broken", "tests/specs/bad"]
HOSTILE = "tests/specs/hostile"
MODELINE = "# yaml-language-server: $schema="
# Top-level keys of each kind (baker/src/spec/kind.rs); the rest are shared.
FIBER_KEYS = {"dyes", "fibers", "bake"}
SKIN_KEYS = {"wavelengths", "defaults", "entries", "sweeps", "profiles"}

# Corpus files a JSON Schema cannot reject, and why; `baker validate` must.
NEEDS_BAKER = {
    "fiber_conflict_duplicate_names.yaml": "names unique across a list (up to case)",
    "skin_conflict_duplicate_names.yaml": "names unique across a list (up to case)",
    "fiber_missing_dye_csv.yaml": "a file on disk",
    "fiber_missing_mask_image.yaml": "a file on disk",
    "fiber_missing_polygon_csv.yaml": "a file on disk",
    "fiber_range_lambda_reversed.yaml": "end not below start (one value against another)",
    "skin_range_wavelengths_reversed.yaml": "stop_nm not below start_nm (one value against another)",
    "fiber_range_resolution.yaml": "a divisor of 180° (within 1e-9)",
    "fiber_range_dye_class_peak.yaml": "the peak of the summed bands at 380–780 nm in the class's range",
}


def loader():
    # pure=True: ruamel's C loader is YAML 1.1. Duplicate keys are errors (as in the baker).
    y = YAML(typ="safe", pure=True)
    y.allow_duplicate_keys = False
    return y


def kind_of(doc):
    """The spec kind by top-level keys, as kind.rs decides it (None: neither or both)."""
    if not isinstance(doc, dict):
        return None
    keys = set(doc)
    skin, fiber = bool(keys & SKIN_KEYS), bool(keys & FIBER_KEYS)
    if skin != fiber:
        return "skin" if skin else "fiber"
    return None


def first_error(validator, doc):
    errors = sorted(validator.iter_errors(doc), key=lambda e: list(e.absolute_path))
    if not errors:
        return None
    e = errors[0]
    where = "/".join(str(p) for p in e.absolute_path) or "(top)"
    return f"{where}: {e.message[:90]}"


def baker_verdict(baker, path):
    r = subprocess.run([str(Path(baker).resolve()), "validate", str(path)], capture_output=True, text=True,
                       cwd=path.parent, timeout=120)
    return r.returncode


ENTRY = "{name: a, age: 30, gender: female, location: forearm, xi: 0.5, skin_type: II}"
# Specs the baker accepts that a schema written from the types alone would refuse.
EDGES = {
    "numeric entry name (serde-saphyr reads a plain 123 as text)":
        "entries:\n  - {name: 123, age: 30, gender: female, location: forearm, xi: 0, skin_type: 2}\n",
    "quoted version, skin type as 2.0, photons as 4e6":
        f'version: "1"\nprofiles: {{photons: 4e6}}\nentries:\n  - {ENTRY.replace("II", "2.0")}\n',
    "required fields from defaults, melanin from defaults":
        "defaults: {age: 40, gender: male, location: face, xi: 1, melanosome_fraction: 0.1}\n"
        "entries:\n  - {name: a}\nsweeps:\n  - {name: 's{age}', age: [30, 50]}\n",
    "null for an optional field, a one-value list in a sweep":
        "profiles: {seed: null}\nsweeps:\n  - {name: s, age: [30], gender: female, "
        "location: palm, xi: 0, skin_type: [VI]}\n",
    "skin_type: null beside melanosome_fraction (null is absent)":
        "entries:\n  - {name: a, age: 30, gender: female, location: forearm, xi: 0.5, "
        "skin_type: null, melanosome_fraction: 0.1}\n",
    "a boost with noise_target 0":
        f"profiles: {{max_photon_boost: 4, noise_target: 0}}\nentries:\n  - {ENTRY}\n",
    "an ellipse, several sections of a generator, f32 keeping 20 bits":
        "bake: {precision: f32, keep_bits: 20}\nfibers:\n"
        "  - {name: e, type: silk, section: {shape: ellipse, ratio: 0.5}}\n"
        "  - {name: g, type: cotton, sections: 3, section: {shape: cotton_raw}}\n",
    "a spec dye used by a fiber and a sweep":
        "dyes:\n  - {name: mine, class: reactive, bands: [{peak_nm: 500, fwhm_nm: 80, "
        "peak_eps_l_per_mg_cm: 0.01}]}\nfibers:\n  - {name: a, type: silk, dye: mine, "
        "depth_of_shade_percent: 1}\n  - {name: b, type: wool, sweep: {dyes: [mine, "
        "reactive_blue_19], depth_of_shade_percent: [0.5, 1.0], undyed: true}}\n",
}


def edges(baker, y, validators, failures):
    """EDGES through the baker (must accept) and the schema (must accept)."""
    import tempfile
    ok = 0
    with tempfile.TemporaryDirectory() as d:
        for i, (what, text) in enumerate(EDGES.items()):
            path = Path(d) / f"edge{i}.yaml"
            path.write_text(text)
            rc = baker_verdict(baker, path)
            if rc != 0:
                failures.append(f"edge case {what!r}: baker validate exited {rc}, expected 0")
                continue
            doc = y.load(text)
            err = first_error(validators[kind_of(doc)], doc)
            if err:
                failures.append(f"edge case {what!r}: the baker accepts it, the schema does not: {err}")
            else:
                ok += 1
    return ok


def hostile(baker, y, validators, failures):
    """Specs of the hostile corpus the baker accepts, validated (the baker runs first: an
    alias bomb is never loaded here)."""
    ok = checked = 0
    for path in sorted((ROOT / HOSTILE).glob("*.yaml")):
        if baker_verdict(baker, path) != 0:
            continue
        checked += 1
        rel = path.relative_to(ROOT)
        try:
            doc = y.load(path.read_text())
        except Exception as e:
            failures.append(f"{rel}: the baker accepts it, ruamel.yaml does not load it: {e}")
            continue
        kind = kind_of(doc)
        err = first_error(validators[kind], doc) if kind else "neither kind"
        if err:
            failures.append(f"{rel}: the baker accepts it, the {kind} schema does not: {err}")
        else:
            ok += 1
    return ok, checked


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--baker", default=str(ROOT / "target/release/baker"))
    args = ap.parse_args()
    failures = []

    validators = {}
    for kind, path in SCHEMAS.items():
        schema = json.loads(path.read_text())
        jsonschema.Draft202012Validator.check_schema(schema)
        validators[kind] = jsonschema.Draft202012Validator(schema)
    print(f"schemas: {', '.join(str(p.relative_to(ROOT)) for p in SCHEMAS.values())} "
          "are valid draft 2020-12")

    y = loader()
    shipped = sorted(p for d in SHIPPED for p in (ROOT / d).glob("*.yaml"))
    ok = 0
    for path in shipped:
        rel = path.relative_to(ROOT)
        text = path.read_text()
        doc = y.load(text)
        kind = kind_of(doc)
        if kind is None:
            failures.append(f"{rel}: neither a skin nor a fiber spec")
            continue
        first = text.splitlines()[0] if text else ""
        if not first.startswith(MODELINE):
            failures.append(f"{rel}: does not start with `{MODELINE}…`")
        else:
            target = (path.parent / first[len(MODELINE):].strip()).resolve()
            if target != SCHEMAS[kind]:
                failures.append(f"{rel}: $schema points at {target}, not the {kind} schema")
        err = first_error(validators[kind], doc)
        if err:
            failures.append(f"{rel} ({kind}): {err}")
        else:
            ok += 1
    print(f"shipped specs: {ok} of {len(shipped)} validate against their schema")

    corpus = sorted(p for d in CORPUS for p in (ROOT / d).glob("*.yaml"))
    rows = []
    accepted = set()
    for path in corpus:
        rel = str(path.relative_to(ROOT))
        try:
            doc = y.load(path.read_text())
        except Exception as e:  # ruamel's YAMLError and its duplicate-key error
            verdict = f"rejected at YAML load ({type(e).__name__})"
        else:
            kind = kind_of(doc)
            kinds = [kind] if kind else list(validators)
            errs = [first_error(validators[k], doc) for k in kinds]
            if all(errs):
                verdict = f"rejected: {errs[0]}"
            else:
                verdict = "accepted: needs the baker"
                accepted.add(path.name)
        rc = baker_verdict(args.baker, path)
        if rc != 2:
            failures.append(f"{rel}: baker validate exited {rc}, expected 2")
        rows.append((rel, verdict, f"exit {rc}" + (" (rejected)" if rc == 2 else "")))

    w = max(len(r[0]) for r in rows)
    v = min(max(len(r[1]) for r in rows), 100)
    print(f"\n{'file':<{w}}  {'schema verdict':<{v}}  baker verdict")
    for f, s, b in rows:
        print(f"{f:<{w}}  {s[:v]:<{v}}  {b}")
    for name in sorted(accepted - set(NEEDS_BAKER)):
        failures.append(f"{name}: the schema accepts it, but it is not in NEEDS_BAKER")
    for name in sorted(set(NEEDS_BAKER) - accepted):
        failures.append(f"{name}: in NEEDS_BAKER, but the schema now rejects it (remove it)")
    rejected = len(corpus) - len(accepted)
    hostile_ok, hostile_checked = hostile(args.baker, y, validators, failures)
    edges_ok = edges(args.baker, y, validators, failures)
    print(f"\ncorpus: {len(corpus)} files; the schema rejects {rejected}, "
          f"{len(accepted)} need the baker:")
    for name in sorted(accepted):
        print(f"  {name}: {NEEDS_BAKER.get(name, '?')}")

    print(f"hostile corpus: {hostile_checked} specs the baker accepts, {hostile_ok} of them "
          "validate against their schema")
    print(f"edge cases the baker accepts: {edges_ok} of {len(EDGES)} validate")
    if failures:
        print("\nFAILED:")
        for f in failures:
            print(f"  {f}")
        return 1
    print("\nok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
