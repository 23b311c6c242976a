#!/usr/bin/env python3
"""Writes docs/scenes/glass-sun.gltf: a grey ground, a white cube and a red-glass cube
(KHR_materials_transmission + KHR_materials_volume: attenuation colour (0.9, 0.25, 0.15) at
0.4 m, thickness 1) lit by a 3000 lux directional sun, with a camera. Used for the pictures in
docs/ (issue 15: coloured glass and a sun-lit scene at default settings).

`--moving OUT.gltf`: the same scene with the white cube sliding 1.2 m to the left and back
over 2 s (LINEAR keys), a sun-lit animation for benchmarks."""
import base64, json, math, struct, sys
from pathlib import Path


sys.path.insert(0, str(Path(__file__).parent / "suite"))
from make_scenes import cube as box  # noqa: E402  (one box generator for every scene script)


def cube(c, h):
    """Cube centred at c with half-size h: the suite's box with equal half-sizes."""
    return box(c, (h, h, h))


def ground(s):
    pos = [(-s, 0, -s), (-s, 0, s), (s, 0, s), (s, 0, -s)]
    return pos, [(0, 1, 0)] * 4, [0, 1, 2, 0, 2, 3]


meshes = [ground(6.0), cube((-0.8, 0.5, 0.0), 0.5), cube((0.8, 0.5, 0.0), 0.5)]
buf = bytearray()
views, accessors, gl_meshes = [], [], []
for mi, (pos, nrm, idx) in enumerate(meshes):
    prim = {}
    for name, data, fmt, typ in [("POSITION", pos, "3f", "VEC3"), ("NORMAL", nrm, "3f", "VEC3")]:
        off = len(buf)
        for p in data:
            buf += struct.pack("<" + fmt, *p)
        views.append({"buffer": 0, "byteOffset": off, "byteLength": len(buf) - off})
        acc = {"bufferView": len(views) - 1, "componentType": 5126, "count": len(data), "type": typ}
        if name == "POSITION":
            acc["min"] = [min(p[i] for p in data) for i in range(3)]
            acc["max"] = [max(p[i] for p in data) for i in range(3)]
        accessors.append(acc)
        prim.setdefault("attributes", {})[name] = len(accessors) - 1
    off = len(buf)
    for i in idx:
        buf += struct.pack("<H", i)
    while len(buf) % 4:
        buf += b"\0"
    views.append({"buffer": 0, "byteOffset": off, "byteLength": 2 * len(idx)})
    accessors.append({"bufferView": len(views) - 1, "componentType": 5123, "count": len(idx), "type": "SCALAR"})
    prim["indices"] = len(accessors) - 1
    prim["material"] = mi
    gl_meshes.append({"primitives": [prim]})

# Sun: 3000 lux, from the upper left front (the light travels along the node's −Z).
yaw, pitch = math.radians(-35), math.radians(-50)
qy = (0, math.sin(yaw / 2), 0, math.cos(yaw / 2))
qx = (math.sin(pitch / 2), 0, 0, math.cos(pitch / 2))
def qmul(a, b):
    ax, ay, az, aw = a; bx, by, bz, bw = b
    return (aw*bx + ax*bw + ay*bz - az*by, aw*by - ax*bz + ay*bw + az*bx,
            aw*bz + ax*by - ay*bx + az*bw, aw*bw - ax*bx - ay*by - az*bz)
sun_q = qmul(qy, qx)
cam_pitch = math.radians(-18)
doc = {
    "asset": {"version": "2.0", "generator": "chronolux scripts/make_glass_sun_scene.py"},
    "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_volume"],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "sun", "type": "directional", "intensity": 3000.0, "color": [1.0, 0.96, 0.9]}]}},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2, 3, 4]}],
    "nodes": [
        {"name": "ground", "mesh": 0}, {"name": "white cube", "mesh": 1},
        {"name": "red glass", "mesh": 2},
        {"name": "sun", "rotation": list(sun_q), "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "camera", "camera": 0, "translation": [0.0, 1.9, 5.2],
         "rotation": [math.sin(cam_pitch / 2), 0, 0, math.cos(cam_pitch / 2)]},
    ],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.05}}],
    "meshes": gl_meshes,
    "materials": [
        {"name": "ground", "pbrMetallicRoughness": {"baseColorFactor": [0.45, 0.45, 0.45, 1], "metallicFactor": 0, "roughnessFactor": 0.9}},
        {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.85, 0.85, 0.85, 1], "metallicFactor": 0, "roughnessFactor": 0.6}},
        {"name": "red glass", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0.0},
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                        "KHR_materials_volume": {"thicknessFactor": 1.0, "attenuationDistance": 0.4,
                                                 "attenuationColor": [0.9, 0.25, 0.15]}}},
    ],
    "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(buf)).decode()}],
    "bufferViews": views,
    "accessors": accessors,
}
args = sys.argv[1:]
if args[:1] == ["--moving"]:
    args = args[1:]
    times, moves = [0.0, 1.0, 2.0], [(0.0, 0.0, 0.0), (-1.2, 0.0, 0.0), (0.0, 0.0, 0.0)]
    off = len(buf)
    for t in times:
        buf += struct.pack("<f", t)
    views.append({"buffer": 0, "byteOffset": off, "byteLength": len(buf) - off})
    accessors.append({"bufferView": len(views) - 1, "componentType": 5126, "count": 3,
                      "type": "SCALAR", "min": [0.0], "max": [2.0]})
    off = len(buf)
    for m in moves:
        buf += struct.pack("<3f", *m)
    views.append({"buffer": 0, "byteOffset": off, "byteLength": len(buf) - off})
    accessors.append({"bufferView": len(views) - 1, "componentType": 5126, "count": 3, "type": "VEC3"})
    doc["animations"] = [{"name": "slide", "samplers": [
        {"input": len(accessors) - 2, "output": len(accessors) - 1, "interpolation": "LINEAR"}],
        "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}]}]
    doc["buffers"][0] = {"byteLength": len(buf), "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(buf)).decode()}
out = Path(args[0] if args else Path(__file__).parent.parent / "docs/scenes/glass-sun.gltf")
out.write_text(json.dumps(doc, indent=1))
print(out)
