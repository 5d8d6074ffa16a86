#!/usr/bin/env bash
# Blender as a Python module (the bpy package, 375 MB) in a venv of its own, .venv-blender, for
# tests/io/test_blendshapes.py, which opens the blendshape glTF in Blender's own glTF importer.
# bpy 5.0 wants Python 3.11 and numpy < 2, so it cannot share the project's venv.
# Usage: bash tools/blender_venv.sh [PYTHON3.11]   (does nothing when the venv is there)
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${1:-$(command -v python3.11 || command -v python3)}
BPY_VERSION=5.0.1
if [ -x .venv-blender/bin/python ] && .venv-blender/bin/python -c "import bpy" 2>/dev/null; then
  exit 0
fi
"$PY" -m venv .venv-blender
.venv-blender/bin/python -m pip install -q "bpy==$BPY_VERSION"
