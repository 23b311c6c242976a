#!/bin/bash
# OIDN told that the albedo and normal passes are noise-free (cleanAux) against before, at
# equal HDR-FLIP (protocol: q.sh). A: main at 9d91885; B: a throwaway build driving the
# filter through the oidn crate's raw bindings with cleanAux (cleanaux.txt). Meant as two
# interleaved rounds of stbpt N = 8, K = 8 and one of path each; stopped after before-a,
# before-b and clean-a, which already showed the loss.
set -u
OUT=${OUT:-$(cd "$(dirname "$0")" && pwd)}
A=${A:?}; B=${B:?}; CM=${CM:?}; REFS=${REFS:?}
. "$(dirname "$0")/q.sh"
for r in a b; do
  q $A before-$r-il8-k8 $IL8
  q $B clean-$r-il8-k8 $IL8
done
q $A before-path $PATH_ARGS
q $B clean-path $PATH_ARGS
