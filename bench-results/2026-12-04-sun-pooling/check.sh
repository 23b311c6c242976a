#!/bin/bash
# The sun-lit outdoor animation (sun-moving.gltf: scripts/make_glass_sun_scene.py --moving) rendered
# at the default by two builds, before (OLD) and after (NEW) the sun's shadow rays got a region of
# their own in dept::reuse::Validity; prints the frames whose EXR differ and each run's light_spp.
OLD=${OLD:?binary before} NEW=${NEW:?binary after}
cd "$(dirname "$0")"
for b in OLD NEW; do
  rm -rf /tmp/sun-$b
  ${!b} render sun-moving.gltf --frames 0..12 --resolution 64x64 --threads 1 --no-preview --output /tmp/sun-$b > /dev/null 2>&1
  python3 -c "import json; print('$b light_spp', sorted({r['stats'].get('light_spp') for r in json.load(open('/tmp/sun-$b/run.json'))['frames']}))"
done
for f in /tmp/sun-OLD/frame_*.exr; do cmp -s $f /tmp/sun-NEW/$(basename $f) || echo "$(basename $f) differs"; done
echo compared
