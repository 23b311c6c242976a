#!/bin/bash
# `--denoise-quality fast` against the default (high) with the committed option, at equal
# HDR-FLIP (protocol: q.sh), stbpt N = 8, K = 8, one round.
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
BIN=${BIN:?}; CM=${CM:?}; REFS=${REFS:?}
. "$(dirname "$0")/q.sh"
q $BIN option-high-il8-k8 $IL8
q $BIN option-fast-il8-k8 $IL8 --denoise-quality fast
