B=./chronolux-6b79ad2
uptime > bench2.uptime
$B bench quality ../shared/peers/cornell-moving.glb --method ic-selective --baseline pm-ic \
  --reference ref-cm --frames 4..16 --target-flip 0.12,0.11,0.1,0.095 \
  --start-effort 8 --max-effort 32 --threads 1 --json --report cm2.md > cm2.json 2> cm2.log
uptime >> bench2.uptime
$B bench quality movlight.gltf --stage cornell --method ic-selective --baseline pm-ic \
  --reference ref-light --frames 0..12 --target-flip 0.077,0.075,0.07 \
  --start-effort 4 --max-effort 16 --threads 1 --json --report light2.md > light2.json 2> light2.log
uptime >> bench2.uptime
