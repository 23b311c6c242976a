#!/usr/bin/env python3
# The moving-light scene of BENCHMARKS.md, issue 13 (ic-selective): writes movlight.gltf
# (a point light moving under the ceiling while a cube slides; use with --stage cornell).
import json, struct, base64
# Rug (1.2 x 1.2 quad at y = 0) and a 0.3 cube; a point light moving along x under the
# ceiling while the cube slides along z (2 s, LINEAR, there and back).
buf = bytearray()
def add(data, fmt):
    global buf
    while len(buf) % 4: buf += b'\0'
    off = len(buf)
    for v in data: buf += struct.pack(fmt, *v) if isinstance(v, tuple) else struct.pack(fmt, v)
    return off, len(buf) - off
views, accs = [], []
def accessor(data, fmt, typ, ctype, target=None, minmax=False):
    off, ln = add(data, fmt)
    v = {"buffer": 0, "byteOffset": off, "byteLength": ln}
    if target: v["target"] = target
    views.append(v)
    a = {"bufferView": len(views) - 1, "componentType": ctype, "count": len(data), "type": typ}
    if minmax:
        if typ == "SCALAR":
            a["min"], a["max"] = [min(data)], [max(data)]
        else:
            a["min"] = [min(p[i] for p in data) for i in range(3)]
            a["max"] = [max(p[i] for p in data) for i in range(3)]
    accs.append(a)
    return len(accs) - 1
h = 0.6
rug_p = accessor([(-h,0,-h),(h,0,-h),(h,0,h),(-h,0,h)], "<3f", "VEC3", 5126, 34962, True)
rug_n = accessor([(0,1,0)]*4, "<3f", "VEC3", 5126, 34962)
rug_i = accessor([0,2,1,0,3,2], "<H", "SCALAR", 5123, 34963)
c = 0.15
faces = []  # 24 verts with normals
pos, nor, idx = [], [], []
for axis in range(3):
    for sgn in (-1, 1):
        n = [0,0,0]; n[axis] = sgn
        u = [0,0,0]; u[(axis+1)%3] = 1
        v = [0,0,0]; v[(axis+2)%3] = 1
        base = len(pos)
        for (a, b) in ((-1,-1),(1,-1),(1,1),(-1,1)):
            p = [n[i]*c + u[i]*a*c + v[i]*b*c for i in range(3)]
            p[1] += c
            pos.append(tuple(p)); nor.append(tuple(n))
        if sgn > 0: idx += [base, base+1, base+2, base, base+2, base+3]
        else: idx += [base, base+2, base+1, base, base+3, base+2]
cube_p = accessor(pos, "<3f", "VEC3", 5126, 34962, True)
cube_n = accessor(nor, "<3f", "VEC3", 5126, 34962)
cube_i = accessor(idx, "<H", "SCALAR", 5123, 34963)
times = [0.0, 1.0, 2.0]
t_acc = accessor(times, "<f", "SCALAR", 5126, None, True)
cube_t = accessor([(0.25,0,-0.35),(0.25,0,0.35),(0.25,0,-0.35)], "<3f", "VEC3", 5126)
lamp_t = accessor([(-0.6,1.4,0.2),(0.6,1.4,0.2),(-0.6,1.4,0.2)], "<3f", "VEC3", 5126)
gltf = {
 "asset": {"version": "2.0", "generator": "chronolux issue-13 benchmark (hand-written)"},
 "extensionsUsed": ["KHR_lights_punctual"],
 "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1.0, 0.85, 0.6], "intensity": 1.5}]}},
 "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
 "nodes": [
   {"name": "rug", "mesh": 0},
   {"name": "cube", "mesh": 1, "translation": [0.25, 0, -0.35]},
   {"name": "lamp", "translation": [-0.6, 1.4, 0.2], "extensions": {"KHR_lights_punctual": {"light": 0}}}],
 "materials": [
   {"name": "rug", "pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.5, 0.8, 1], "metallicFactor": 0, "roughnessFactor": 1}},
   {"name": "cube", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1], "metallicFactor": 0, "roughnessFactor": 1}}],
 "meshes": [
   {"name": "rug", "primitives": [{"attributes": {"POSITION": rug_p, "NORMAL": rug_n}, "indices": rug_i, "material": 0}]},
   {"name": "cube", "primitives": [{"attributes": {"POSITION": cube_p, "NORMAL": cube_n}, "indices": cube_i, "material": 1}]}],
 "animations": [{"name": "move", "samplers": [
     {"input": t_acc, "output": cube_t, "interpolation": "LINEAR"},
     {"input": t_acc, "output": lamp_t, "interpolation": "LINEAR"}],
   "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}},
                {"sampler": 1, "target": {"node": 2, "path": "translation"}}]}],
 "accessors": accs, "bufferViews": views,
 "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(buf)).decode()}],
}
json.dump(gltf, open("movlight.gltf", "w"), indent=1)
