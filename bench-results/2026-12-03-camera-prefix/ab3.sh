#!/usr/bin/env bash
# CPU seconds (user + sys) of one `render` per binary, A and B alternating ROUNDS times,
# one thread, no denoiser: cornell-moving 256², frames 0-7, stbpt N = 2, K = 8, 1 spp.
# usage: A=<before> B=<after> CM=<cornell-moving.glb> ab3.sh OUT ROUNDS
set -euo pipefail
OUT=$1; ROUNDS=${2:-5}; mkdir -p "$OUT"
for r in $(seq 1 "$ROUNDS"); do for ab in A B; do bin=${!ab}
  rm -rf "$OUT/img"
  /usr/bin/time -f "$ab$r %U %S" -a -o "$OUT/times.txt" "$bin" render "$CM" --method stbpt \
    --set window=8 --set interleave=2 --spp 1 --frames 0..8 --resolution 256x256 --max-depth 8 \
    --threads 1 --no-preview --output "$OUT/img" > /dev/null 2>&1
done; done
python3 - "$OUT/times.txt" <<'PY'
import sys
t = {}
for line in open(sys.argv[1]):
    k, u, s = line.split(); t[k] = float(u) + float(s)
rounds = sorted({k[1:] for k in t}, key=int)
for r in rounds:
    print(f"round {r}: A {t['A'+r]:.2f}  B {t['B'+r]:.2f}  B/A {t['B'+r]/t['A'+r]:.3f}")
ra = [t['B'+r]/t['A'+r] for r in rounds]
print(f"B/A mean {sum(ra)/len(ra):.3f}, range {min(ra):.3f}-{max(ra):.3f}")
PY
