#!/bin/bash
# OIDN's Fast quality against its default (High) at equal HDR-FLIP (protocol: q.sh), stbpt
# N = 8, K = 8 and path, with the throwaway build BIN whose denoiser uses Fast when
# CHRONOLUX_OIDN_FAST is set (oidn-env.patch; the runs were made with the build of its
# first half, the same code for this variable). Two rounds.
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
BIN=${BIN:?}; CM=${CM:?}; REFS=${REFS:?}
. "$(dirname "$0")/q.sh"
for r in a b; do
  CHRONOLUX_OIDN_FAST=1 q $BIN fast-$r-il8-k8 $IL8
  q $BIN high-$r-il8-k8 $IL8
  CHRONOLUX_OIDN_FAST=1 q $BIN fast-$r-path $PATH_ARGS
done
