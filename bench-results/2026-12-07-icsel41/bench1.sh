B=./chronolux-382a3e9
$B bench quality ../shared/peers/cornell-moving.glb --method ic-selective --baseline pm-ic \
  --reference ref-cm --frames 4..16 --target-flip 0.12,0.1,0.09,0.085 \
  --start-effort 8 --max-effort 32 --threads 1 --json --report cm1.md > cm1.json 2> cm1.log
$B bench quality movlight.gltf --stage cornell --method ic-selective --baseline pm-ic \
  --reference ref-light --frames 0..12 --target-flip 0.09,0.08,0.077,0.075 \
  --start-effort 4 --max-effort 32 --threads 1 --json --report light1.md > light1.json 2> light1.log
