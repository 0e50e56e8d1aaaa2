#!/bin/bash
# Default spec (6°, specs/fibers.yaml) at 8192 photons per direction: more draws per event
# met from outside (split) against each fiber's current estimators. Efficiency
# 1/(noise² × s), noise = the manifest's median per-bin relative SE. One bake at a time.
#   bash scan6deg.sh BAKER > log-6deg.txt 2>&1
set -e
cd "$(dirname "$0")/../../.."
B=$(realpath "$1")
T=$(mktemp -d)
variant() { # NAME PHOTONS "ENTRIES" k=v ...
  local name=$1 ph=$2 entries=$3; shift 3
  python3 - "$T/$name.yaml" "$@" <<'PY'
import re, sys
s = open("specs/fibers.yaml").read()
s = re.sub(r"^    estimators: .*\n", "", s, flags=re.M)
for kv in sys.argv[2:]:
    k, v = kv.split("=", 1)
    pat = re.compile(r"^(  " + re.escape(k) + r":)\s*\S+", re.M)
    s = pat.sub(r"\g<1> " + v, s) if pat.search(s) else s.replace("  seed: 1\n", f"  seed: 1\n  {k}: {v}\n", 1)
open(sys.argv[1], "w").write(s)
PY
  local o; o="$T/$name-$(echo "$entries" | md5sum | cut -c1-8)"
  "$B" bake --threads 2 -q --photons "$ph" $entries -o "$o" "$T/$name.yaml"
  python3 - "$name" "$o/$name" <<'PY'
import json, sys
name, d = sys.argv[1:]
m = json.load(open(d + "/manifest.json"))
t = {e["entry"]: e for e in json.load(open(d + "/timing.json"))["entries"]}
print(name)
for e in m["entries"]:
    s, z = t[e["name"]]["seconds"], e["noise"]["median_rel_se"]
    print(f"  {e['name']:20s} {s:8.2f} s  noise {z:.4f}  1/(noise²·s) {1 / (z * z * s):9.2f}  "
          f"estimators {e['split']}/{e['exit_draws']}/{e['expected_exits']}")
PY
}
E1="--entry polyester --entry polyester_trilobal --entry cotton_mercerised --entry wool"
E2="--entry silk --entry cotton"
for E in "$E1" "$E2"; do
  variant split2-exit4 8192 "$E" split=2 exit_draws=4
  variant split8-exit4 8192 "$E" split=8 exit_draws=4
  variant split16-exit4 8192 "$E" split=16 exit_draws=4
  variant expected-all 8192 "$E" expected_exits=all
  variant split8-exit4-expected 8192 "$E" split=8 exit_draws=4 expected_exits=all
done
rm -rf "$T"
echo done
