#!/usr/bin/env bash
# Open Job Description (Deadline Cloud) template test, run by .ci/run: `openjd check` of the
# template `chronolux farm openjd` writes, then `openjd run` of two of its chunks (segment
# tasks) locally; their frames must equal the single-run render bit for bit.
# Usage: scripts/ci/openjd.sh PATH/TO/chronolux [PYTHON_VENV_DIR]
set -euo pipefail
BIN=$(readlink -f "$1")
VENV=${2:-.venv-openjd}
WORK=$(mktemp -d /tmp/chronolux-openjd.XXXXXX)
log() { echo "openjd-test: $*"; }
if [ ! -x "$VENV/bin/openjd" ]; then
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install -q openjd-cli
fi
OPENJD="$VENV/bin/openjd"

ARGS=(--method stbpt --window 1 --frames 0..6 --resolution 16x16 --spp 1 --no-preview)
"$BIN" render "${ARGS[@]}" --output "$WORK/single" 2>/dev/null
"$BIN" farm openjd "${ARGS[@]}" --segment-length 2 --output "$WORK/farm"
"$OPENJD" check "$WORK/farm/job.template.yaml"
for seg in 0 2; do
    "$OPENJD" run "$WORK/farm/job.template.yaml" --step Render --task-param Segment=$seg >"$WORK/run-$seg.log" 2>&1 \
        || { cat "$WORK/run-$seg.log"; log "FAILED: openjd run of segment $seg"; exit 1; }
done
for f in 0 1 4 5; do
    cmp -s "$WORK/farm/frame_000$f.exr" "$WORK/single/frame_000$f.exr" \
        || { log "FAILED: frame $f of the openjd chunks differs from the single run"; exit 1; }
done
for f in 2 3; do
    [ ! -e "$WORK/farm/frame_000$f.exr" ] || { log "FAILED: frame $f written by a chunk that does not own it"; exit 1; }
done
rm -rf "$WORK"
log "passed (template valid, 2 chunks run locally, frames equal the single run)"
