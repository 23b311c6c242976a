#!/usr/bin/env bash
# Builds the installable add-on: blender/chronolux_blender.zip (Edit > Preferences >
# Add-ons > Install from Disk). Equivalent to `cd blender && zip -r chronolux_blender.zip
# chronolux_blender -x '*/__pycache__/*'`.
set -euo pipefail
cd "$(dirname "$0")"
rm -f chronolux_blender.zip
python3 - <<'PY'
import os, zipfile
with zipfile.ZipFile("chronolux_blender.zip", "w", zipfile.ZIP_DEFLATED) as z:
    for root, dirs, files in os.walk("chronolux_blender"):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        for f in sorted(files):
            if f.endswith(".py"):
                z.write(os.path.join(root, f))
PY
echo "$(pwd)/chronolux_blender.zip"
