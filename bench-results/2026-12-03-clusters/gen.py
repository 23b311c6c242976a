# A heavy animated glTF: a UV sphere (2*S*(R-1) triangles) sliding over a finely
# tessellated floor (2*F*F triangles), one point light. For scaling checks only.
import json, struct, math, sys
S, R, F = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
pos, idx = [], []
def sphere(cx, cy, cz, r):
    base = len(pos)
    for i in range(R + 1):
        th = math.pi * i / R
        for j in range(S):
            ph = 2 * math.pi * j / S
            pos.append((cx + r * math.sin(th) * math.cos(ph), cy + r * math.cos(th), cz + r * math.sin(th) * math.sin(ph)))
    for i in range(R):
        for j in range(S):
            a, b = base + i * S + j, base + i * S + (j + 1) % S
            c, d = a + S, b + S
            if i > 0: idx.append((a, b, c))
            if i < R - 1: idx.append((b, d, c))
sphere(0, 0, 0, 0.5)
sph_pos, sph_idx = pos, idx
pos, idx = [], []
for i in range(F + 1):
    for j in range(F + 1):
        pos.append((-2 + 4 * i / F, -0.5, -2 + 4 * j / F))
for i in range(F):
    for j in range(F):
        a = i * (F + 1) + j
        idx.append((a, a + 1, a + F + 1)); idx.append((a + 1, a + F + 2, a + F + 1))
floor_pos, floor_idx = pos, idx
blob = b''; views = []; accs = []
def add(data, fmt, count, typ, ctype, target, minmax=None):
    global blob
    off = len(blob); blob += data
    while len(blob) % 4: blob += b'\0'
    views.append({"buffer": 0, "byteOffset": off, "byteLength": len(data), **({"target": target} if target else {})})
    a = {"bufferView": len(views) - 1, "componentType": ctype, "count": count, "type": typ}
    if minmax: a["min"], a["max"] = minmax
    accs.append(a); return len(accs) - 1
def mesh_accs(p, t):
    mn = [min(v[k] for v in p) for k in range(3)]; mx = [max(v[k] for v in p) for k in range(3)]
    pa = add(b''.join(struct.pack('<3f', *v) for v in p), None, len(p), "VEC3", 5126, 34962, (mn, mx))
    ia = add(b''.join(struct.pack('<3I', *v) for v in t), None, 3 * len(t), "SCALAR", 5125, 34963)
    return pa, ia
sp, si = mesh_accs(sph_pos, sph_idx); fp, fi = mesh_accs(floor_pos, floor_idx)
times = [0.0, 1.0, 2.0]; tr = [(-1, 0.2, 0), (1, 0.2, 0), (-1, 0.2, 0)]
ta = add(b''.join(struct.pack('<f', t) for t in times), None, 3, "SCALAR", 5126, None, ([0.0], [2.0]))
va = add(b''.join(struct.pack('<3f', *v) for v in tr), None, 3, "VEC3", 5126, None)
g = {"asset": {"version": "2.0", "generator": "chronolux heavy gen.py"},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 40.0, "color": [1, 1, 1]}]}},
  "scene": 0, "scenes": [{"nodes": [0, 1, 2, 3]}],
  "nodes": [{"mesh": 0, "translation": [-1, 0.2, 0]}, {"mesh": 1},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0, 2, 1]},
            {"camera": 0, "translation": [0, 1.0, 4.0], "rotation": [-0.0998, 0, 0, 0.995]}],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05, "aspectRatio": 1.0}}],
  "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.3, 0.2, 1], "metallicFactor": 0, "roughnessFactor": 0.6}},
                {"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0, "roughnessFactor": 1}}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": sp}, "indices": si, "material": 0}]},
             {"primitives": [{"attributes": {"POSITION": fp}, "indices": fi, "material": 1}]}],
  "animations": [{"channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
                  "samplers": [{"input": ta, "output": va, "interpolation": "LINEAR"}]}],
  "accessors": accs, "bufferViews": views, "buffers": [{"byteLength": len(blob)}]}
j = json.dumps(g).encode()
while len(j) % 4: j += b' '
out = struct.pack('<III', 0x46546C67, 2, 12 + 8 + len(j) + 8 + len(blob)) + struct.pack('<II', len(j), 0x4E4F534A) + j + struct.pack('<II', len(blob), 0x004E4942) + blob
open(sys.argv[4], 'wb').write(out)
print(len(sph_idx), "sphere triangles,", len(floor_idx), "floor triangles")
