#!/usr/bin/env bash
# Byte-identity of every output across a refactor: builds REV (default: the merge base with
# origin/main or HEAD~1) in a temporary worktree, runs the same commands with both binaries and
# compares every file they write byte for byte. Wall-clock files (timing.json, cache unit
# bytes) are compared without their seconds; the stamps (`.baked`, which digest the executable)
# are not compared.
#
#   bash validation/check_identical.sh [REV]        # e.g. 4422149
#   BAKER_IDENT_REF_BIN=/path/to/old/baker BAKER_IDENT_DIR=/tmp/x bash validation/check_identical.sh
#
# Covers: `baker bake` of specs/fitzpatrick.yaml (3 entries, reduced photons) and
# specs/fibers.yaml (reduced photons), `baker export` to every skin and fiber target, and
# `baker mc` on a stack file, an .mci file (with .mco) and a spec entry.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
rev=${1:-HEAD~1}
work=${BAKER_IDENT_DIR:-/tmp/baker-identical}
mkdir -p "$work"
ref_bin=${BAKER_IDENT_REF_BIN:-}  # a prebuilt reference binary skips the worktree build
if [ -z "$ref_bin" ]; then
    ref_src="$work/ref-src"
    if [ ! -d "$ref_src" ]; then git -C "$repo" worktree add --detach "$ref_src" "$rev" >/dev/null; fi
    git -C "$ref_src" checkout --quiet --detach "$rev"
    echo "building reference $(git -C "$ref_src" rev-parse --short HEAD) ..."
    (cd "$ref_src" && CARGO_TARGET_DIR="$work/ref-target" cargo build --release -q -p baker)
    ref_bin="$work/ref-target/release/baker"
fi
echo "building this tree ..."
(cd "$repo" && cargo build --release -q -p baker)
new_bin="${CARGO_TARGET_DIR:-$repo/target}/release/baker"
export SOURCE_DATE_EPOCH=1700000000
run_all() { # $1 = baker binary, $2 = output folder
    local b=$1 o=$2
    rm -rf "$o"; mkdir -p "$o"
    cd "$repo"
    "$b" bake specs/fitzpatrick.yaml --entry typeI_age20_xi0 --entry typeIII_age50_xi0.5 \
        --entry typeVI_age80_xi1 --photons 2000 --threads 2 -q --out "$o/bake" --plots
    "$b" bake specs/fibers.yaml --photons 64 --threads 2 -q --out "$o/bake"
    local t="$o/bake/fitzpatrick/profiles.bkt"
    for to in burley mtlx blender unreal unity pbrt mitsuba; do
        "$b" export "$t" --to "$to" -o "$o/skin.$to"
    done
    local f; f=$(find "$o/bake/fibers" -name '*.bcsdf' | sort | head -1)
    for to in chiang pbrt mitsuba blender; do
        "$b" export "$f" --to "$to" -o "$o/fiber.$to"
    done
    "$b" mc tests/stacks/skin_with_junction.json --photons 20000 --seed 3 --threads 2 --json > "$o/mc_stack.json"
    (mkdir -p "$o/mci" && cp tests/stacks/two_runs.mci "$o/mci/" && cd "$o/mci" && "$b" mc --mci-in two_runs.mci --photons 5000 --threads 2 > summary.txt)
    "$b" mc --spec specs/fitzpatrick.yaml --entry typeIII_age50_xi0.5 --lambda-nm 550 --photons 20000 --threads 2 --json > "$o/mc_spec.json"
    "$b" fiber trace --help >/dev/null
}
# Both run in the same folder (exports and cache roots name the paths they read and wrote).
run_all "$ref_bin" "$work/run"; rm -rf "$work/ref-out"; mv "$work/run" "$work/ref-out"
run_all "$new_bin" "$work/run"; rm -rf "$work/new-out"; mv "$work/run" "$work/new-out"
strip_time() { # wall-clock figures: JSON fields named *seconds* / *_per_s, summary speed lines
    sed -E -e 's/"[a-z_]*(seconds|_per_s)[a-z_]*": *[0-9.eE+-]+/"T": T/g' -e '/photons\/s/d' "$1"
}
status=0; n=0
while IFS= read -r -d '' f; do
    rel=${f#"$work/ref-out/"}; n=$((n+1))
    g="$work/new-out/$rel"
    if [ ! -e "$g" ]; then echo "missing in this tree: $rel"; status=1; continue; fi
    case "$rel" in
        */timing.json|*/shard.json|mc_*.json|*/summary.txt) cmp -s <(strip_time "$f") <(strip_time "$g") || { echo "differs: $rel"; status=1; } ;;
        */.cache/*) ;;  # unit bytes hold wall-clock seconds; the tables built from them are compared
        */.baked) ;;    # the stamp digests the executable itself: two binaries never share one
        *) cmp -s "$f" "$g" || { echo "differs: $rel"; status=1; } ;;
    esac
done < <(find "$work/ref-out" -type f -print0)
# Cache keys: the units' file names are their keys, and must be the same set.
units() { (cd "$1" && find . -path '*/.cache/*' -type f ! -path '*/roots/*' | sort); }
if ! cmp -s <(units "$work/ref-out") <(units "$work/new-out"); then
    echo "cache unit keys differ:"; diff <(units "$work/ref-out") <(units "$work/new-out") | head; status=1
else
    echo "cache unit keys: $(units "$work/ref-out" | wc -l) identical"
fi
extra=$(cd "$work/new-out" && find . -type f ! -path '*/.cache/*' | sed 's|^\./||' | while read -r r; do [ -e "$work/ref-out/$r" ] || echo "$r"; done)
[ -z "$extra" ] || { echo "only in this tree:"; echo "$extra"; status=1; }
[ $status = 0 ] && echo "identical: $n files (cache units and stamps excluded: wall-clock seconds, executable digest)"
exit $status
