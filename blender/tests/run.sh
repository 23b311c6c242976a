#!/usr/bin/env bash
# Runs the Blender add-on's tests headless: bpy from PyPI (Blender as a Python module),
# the add-on from this folder, the chronolux binary given as $1 (default: the release
# build). $PYTHON: a Python with bpy, numpy, flip-evaluator and OpenEXR (default python3).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${1:-$here/../../target/release/chronolux}"
test -x "$bin" || { echo "error: no chronolux binary at $bin (cargo build --release)" >&2; exit 1; }
CHRONOLUX_BINARY="$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")" \
    exec "${PYTHON:-python3}" "$here/test_addon.py" "${@:2}"
