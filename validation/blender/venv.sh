#!/usr/bin/env bash
# Makes (once) the virtual environment with Blender's `bpy` module that the Blender checks and
# the gallery run in, and prints its python: target/bpy-venv/bin/python.
# bpy needs numpy < 2 and CPython 3.11 (validation/requirements-blender.txt), so it cannot share
# the environment of the other validation scripts (numpy 2).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
venv="$root/target/bpy-venv"
py="$venv/bin/python"
if ! "$py" -c "import bpy" >/dev/null 2>&1; then
    python3 -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' ||
        { echo "error: bpy 5.0 needs CPython 3.11; python3 is $(python3 --version)" >&2; exit 1; }
    python3 -m venv "$venv"
    "$py" -m pip install --quiet --disable-pip-version-check -r "$root/validation/requirements-blender.txt" >&2
fi
echo "$py"
