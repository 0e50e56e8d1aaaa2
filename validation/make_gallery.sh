#!/usr/bin/env bash
# Regenerates the README's gallery, validation/gallery/, from the default bake:
#
#   bash validation/make_gallery.sh
#
# 1. builds the baker and bakes the default specs into out/ (cached: nothing is re-baked when
#    out/fitzpatrick/ and out/fibers/ are complete; ~14 min on 2 cores when they are not);
# 2. installs the validation requirements (Mitsuba 3, numpy, zstandard, …), the Python module
#    (Mitsuba plugin) and makes target/bpy-venv (Blender's bpy);
# 3. skin_contact_sheet.png: the Fitzpatrick database at xi 0.5 through `--to blender`
#    (Random Walk (Skin)), rendered in Cycles (validation/blender/contact_sheet.py);
# 4. cloth_<fiber>.png: a plain weave rendered in Mitsuba 3 with the baked table
#    (baker_bcsdf, left) and its Chiang export (hair, right), cloth.md the differences
#    (validation/render_cloth.py);
# 5. engine_profiles.png/.md: Cycles and Mitsuba 3 against the baked Rd(r) for four entries
#    (validation/check_engine_profiles.py --full);
# 6. fiber_preview_silk.png: the bake's own preview of the silk table.
# About 6 minutes on 2 cores once the bake exists. Work files go to target/gallery/.
set -euo pipefail
cd "$(dirname "$0")/.."
gallery=validation/gallery
work=target/gallery
mkdir -p "$gallery" "$work"

# Mitsuba's LLVM variants (the cloth renders, the plugin's χ² test) compile through the system's
# libLLVM; Dr.Jit 1.x emits llvm.maximum, which Debian 12's default LLVM 14 cannot lower on x86
# ("LLVM ERROR: Cannot select: fmaximum"). Debian 12's libllvm19 can (root; skipped elsewhere).
if command -v apt-get >/dev/null && [ "$(id -u)" = 0 ]; then
    apt-get install -y -qq libllvm19 >/dev/null
fi
cargo build --quiet --release -p baker
baker=target/release/baker
"$baker" bake specs/fitzpatrick.yaml specs/fibers.yaml -o out
pip=(python3 -m pip install --quiet --disable-pip-version-check --root-user-action=ignore)
"${pip[@]}" -r validation/requirements.txt
"${pip[@]}" ./formats/python
bpy="$(bash validation/blender/venv.sh)"

python3 validation/blender/contact_sheet.py --table out/fitzpatrick/profiles.bkt \
    --bpy "$bpy" --baker "$baker" --samples 64 -o "$work/sheet"
cp "$work/sheet/skin_contact_sheet.png" "$gallery/"

python3 validation/render_cloth.py --baker "$baker" --tables out/fibers -o "$work/cloth"
for f in polyester silk cotton wool; do
    cp "$work/cloth/${f}_pair.png" "$gallery/cloth_${f}.png"
done
cp "$work/cloth/cloth.md" "$gallery/"

python3 validation/check_engine_profiles.py --full --baker "$baker" --bpy "$bpy" -o "$work/profiles"
cp "$work/profiles/engine_profiles.png" "$work/profiles/engine_profiles.md" "$gallery/"

cp out/fibers/preview/silk.png "$gallery/fiber_preview_silk.png"
echo "make_gallery: wrote $(ls "$gallery" | wc -l) files to $gallery/"
