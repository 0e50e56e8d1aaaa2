# Shared by the fiber estimator records' scripts (source it with B, a baker build, and T, a
# scratch folder, set; run from the repository root).
# A copy of specs/fibers.yaml with the bake: block's fields set (k=v ...), without the
# fibers' own estimators, baked for some entries at --photons P; prints seconds and noise.
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
  # Each group of entries in a folder of its own (a second group in the same folder would be
  # a subset bake, written to subset/).
  local o; o="$T/$name-$(echo "$entries" | md5sum | cut -c1-8)"
  "$B" bake --threads 2 -q --photons "$ph" $entries -o "$o" "$T/$name.yaml"
  report "$name" "$o/$name"
}
report() { # NAME DIR: per entry seconds, median relative SE, 1/(noise² × seconds)
  python3 - "$1" "$2" <<'PY'
import json, sys
name, d = sys.argv[1:]
m = json.load(open(d + "/manifest.json"))
t = {e["entry"]: e for e in json.load(open(d + "/timing.json"))["entries"]}
print(name)
for e in m["entries"]:
    s, z = t[e["name"]]["seconds"], e["noise"]["median_rel_se"]
    print(f"  {e['name']:20s} {s:8.2f} s  noise {z:.4f}  p90 {e['noise']['p90_rel_se']:.3f}  "
          f"1/(noise²·s) {1 / (z * z * s):9.2f}  photons {e['photons']['total']}  "
          f"estimators {e['split']}/{e['exit_draws']}/{e['expected_exits']}  .bcsdf {e['bcsdf_bytes']} B")
PY
}
