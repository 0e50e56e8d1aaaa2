#!/usr/bin/env bash
# Mutation testing of one physics module with cargo-mutants (configuration: .cargo/mutants.toml).
#
#   bash validation/mutants/run.sh MODULE [cargo-mutants options…]
#
# MODULE is one of skin transport fiber spectral fit profile formats. Each module is tested
# with the tests that exercise it (the unit tests plus the named integration tests), so a
# mutant counts as caught only when those tests fail. Extra options go to cargo-mutants, e.g.
# `--shard 0/8 --sharding round-robin` for a sample, `--iterate` to rerun only what survived,
# `--list` to count. Results land in target/mutants-out/MODULE/mutants.out/ (outcomes.json,
# caught.txt, missed.txt, timeout.txt, unviable.txt); summarise with
# `python3 validation/mutants/summary.py target/mutants-out/*/mutants.out`.
# cargo-mutants builds each run in a scratch copy of the tree; the build folder is shared
# between runs (target/mutants-build, or $CARGO_TARGET_DIR), so only the mutated crates
# rebuild: the dependencies' 15-minute cold build happens once.
# Install once: `cargo install cargo-mutants --locked` (tested with 27.1.0).
set -euo pipefail
cd "$(dirname "$0")/../.."
module=${1:?usage: run.sh MODULE [cargo-mutants options…]}
shift
case "$module" in
skin)      files=('baker/src/skin/**');      tests=(--lib --test table4 --test spectra --test properties --test skin_reference) ;;
spectral)  files=('baker/src/spectral/**');  tests=(--lib --test spectra --test table4 --test properties --test skin_reference) ;;
transport) files=('baker/src/transport/**'); tests=(--lib --test transport --test cli) ;;
fiber)     files=('baker/src/fiber/**');     tests=(--lib --test fiber --test fiber_references) ;;
fit)       files=('baker/src/fit/**');       tests=(--lib --test profiles) ;;
profile)   files=('baker/src/profile/**');   tests=(--lib --test profiles) ;;
formats)   files=('formats/src/**');         tests=() ;;
*) echo "unknown module '$module'; one of: skin transport fiber spectral fit profile formats" >&2; exit 2 ;;
esac
args=()
for f in "${files[@]}"; do args+=(-f "$f"); done
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$PWD/target/mutants-build}
mkdir -p "target/mutants-out/$module"
exec cargo mutants "${args[@]}" -o "target/mutants-out/$module" "$@" -- "${tests[@]}"
