#!/usr/bin/env python3
"""Writes the generated scenes of the issue-40 suite (Python 3.11 stdlib only) as GLB files.

    python3 scripts/suite/make_scenes.py OUT_DIR [--shared ../shared]

Every scene is 48 frames at 24 fps (times f/24 s, f = 0..47), one animation clip, purely
Lambertian materials (`metallicFactor` 0 and `KHR_materials_specular.specularFactor` 0, so
Blender's importer and Chronolux read the same BRDF), one perspective camera (aspect 1):

- `cornell-flythrough.glb`: the still interior. cornell-moving's room (../shared/peers/
  cornell-moving.glb: Blender-exported, the room both renderers already agree on) with its cube
  held still at its frame-0 pose, a sphere and a low box added as furniture, and the camera on a
  path: it flies from outside the open front in through the opening (z 1.08 -> 0.38 m) while
  trucking left to right and turning to keep a point at the back of the room in view. Nothing
  but the camera moves.
- `cornell-dolly.glb`: the glTF twin of `builtin:dolly` (moving camera AND moving object, which
  Cycles cannot read as a built-in): cornell-moving with its sliding cube kept and the camera
  trucking x -0.08 -> +0.08 m and dollying z 1.08 -> 0.90 m, turned to keep the room's centre in
  the middle of the frame (LINEAR keys at 0, 1, 2 s, as the built-in's).
- `rigged-room.glb`: the skinned character staged in a room. ../shared/scenes/RiggedSimple.glb
  (a skinned cylinder bending at its joint, 2.08 s clip) scaled to 0.30 m tall and stood on the
  floor of cornell-moving's room (cube held still), its animation the only clip.
- `outdoor-sun.glb`: an outdoor scene lit by a sun (KHR_lights_punctual directional, 3 W/m^2
  irradiance: Chronolux takes the glTF intensity as irradiance, the Cycles driver sets the sun's
  strength to the same figure; no sky: black background, the camera sees only ground), a
  200 m ground, two still boxes and a box sliding 3 m while turning 90 degrees.
"""
import argparse
import json
import math
import os
import struct
import sys

FRAMES = 48
FPS = 24.0


def read_glb(path):
    b = open(path, "rb").read()
    if b[:4] != b"glTF":
        sys.exit(f"{path}: not a GLB file")
    n = struct.unpack_from("<I", b, 12)[0]
    j = json.loads(b[20:20 + n])
    off = 20 + n
    binc = bytearray()
    if off < len(b):
        m = struct.unpack_from("<I", b, off)[0]
        binc = bytearray(b[off + 8:off + 8 + m])
    return j, binc


class Glb:
    """A glTF document with one binary buffer, grown by the add_* helpers."""

    def __init__(self, j=None, binc=None):
        self.j = j or {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": []}]}
        self.j["asset"]["generator"] = "chronolux scripts/suite/make_scenes.py"
        self.bin = binc if binc is not None else bytearray()
        for k in ("nodes", "meshes", "materials", "accessors", "bufferViews", "animations"):
            self.j.setdefault(k, [])
        self.j.setdefault("buffers", [{"byteLength": 0}])

    def _view(self, data):
        while len(self.bin) % 4:
            self.bin += b"\0"
        off = len(self.bin)
        self.bin += data
        self.j["bufferViews"].append({"buffer": 0, "byteOffset": off, "byteLength": len(data)})
        return len(self.j["bufferViews"]) - 1

    def accessor(self, rows, typ, comp=5126, minmax=False):
        """rows: list of tuples (or of scalars for SCALAR)."""
        flat = [x for r in rows for x in (r if isinstance(r, (tuple, list)) else (r,))]
        fmt = {5126: "f", 5123: "H", 5125: "I"}[comp]
        v = self._view(struct.pack("<%d%s" % (len(flat), fmt), *flat))
        a = {"bufferView": v, "componentType": comp, "count": len(rows), "type": typ}
        if minmax:
            n = len(flat) // len(rows)
            a["min"] = [min(flat[i::n]) for i in range(n)]
            a["max"] = [max(flat[i::n]) for i in range(n)]
        self.j["accessors"].append(a)
        return len(self.j["accessors"]) - 1

    def material(self, name, rgb, emissive=None):
        m = {"name": name, "doubleSided": True,
             "pbrMetallicRoughness": {"baseColorFactor": list(rgb) + [1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
             "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}}
        if emissive:
            m["emissiveFactor"] = list(emissive)
        self.j["materials"].append(m)
        self._ext("KHR_materials_specular")
        return len(self.j["materials"]) - 1

    def _ext(self, name):
        used = self.j.setdefault("extensionsUsed", [])
        if name not in used:
            used.append(name)

    def mesh(self, name, tri, material):
        pos, nrm, idx = tri
        p = self.accessor(pos, "VEC3", minmax=True)
        n = self.accessor(nrm, "VEC3")
        i = self.accessor(idx, "SCALAR", comp=5125)
        self.j["meshes"].append({"name": name, "primitives": [
            {"attributes": {"POSITION": p, "NORMAL": n}, "indices": i, "material": material}]})
        return len(self.j["meshes"]) - 1

    def node(self, name, root=True, **kw):
        self.j["nodes"].append({"name": name, **kw})
        i = len(self.j["nodes"]) - 1
        if root:
            self.j["scenes"][self.j.get("scene", 0)]["nodes"].append(i)
        return i

    def channels(self, node, times, translations=None, rotations=None, anim=0):
        while len(self.j["animations"]) <= anim:
            self.j["animations"].append({"name": "suite", "channels": [], "samplers": []})
        a = self.j["animations"][anim]
        t = self.accessor(times, "SCALAR", minmax=True)
        for path, vals, typ in (("translation", translations, "VEC3"), ("rotation", rotations, "VEC4")):
            if vals is None:
                continue
            a["samplers"].append({"input": t, "output": self.accessor(vals, typ), "interpolation": "LINEAR"})
            a["channels"].append({"sampler": len(a["samplers"]) - 1, "target": {"node": node, "path": path}})

    def write(self, path):
        while len(self.bin) % 4:
            self.bin += b"\0"
        self.j["buffers"] = [{"byteLength": len(self.bin)}]
        js = json.dumps(self.j, separators=(",", ":")).encode()
        js += b" " * ((4 - len(js) % 4) % 4)
        total = 12 + 8 + len(js) + 8 + len(self.bin)
        with open(path, "wb") as f:
            f.write(struct.pack("<4sII", b"glTF", 2, total))
            f.write(struct.pack("<I4s", len(js), b"JSON") + js)
            f.write(struct.pack("<I4s", len(self.bin), b"BIN\0") + bytes(self.bin))
        print(f"wrote {path} ({total} bytes)")


def cube(c, h):
    """Box centred at c with half-sizes h (3-tuple): 24 vertices, face normals."""
    quads = [((0, 0, 1), (1, 0, 0)), ((0, 0, -1), (-1, 0, 0)), ((1, 0, 0), (0, 0, -1)),
             ((-1, 0, 0), (0, 0, 1)), ((0, 1, 0), (1, 0, 0)), ((0, -1, 0), (1, 0, 0))]
    pos, nrm, idx = [], [], []
    for n, u in quads:
        v = (n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0])
        base = len(pos)
        for a, b in [(-1, -1), (1, -1), (1, 1), (-1, 1)]:
            pos.append(tuple(c[i] + h[i] * (n[i] + a * u[i] + b * v[i]) for i in range(3)))
            nrm.append(n)
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, idx


def sphere(c, r, seg=32, rings=16):
    pos, nrm, idx = [], [], []
    for i in range(rings + 1):
        th = math.pi * i / rings
        for k in range(seg + 1):
            ph = 2 * math.pi * k / seg
            n = (math.sin(th) * math.cos(ph), math.cos(th), -math.sin(th) * math.sin(ph))
            pos.append(tuple(c[j] + r * n[j] for j in range(3)))
            nrm.append(n)
    row = seg + 1
    for i in range(rings):
        for k in range(seg):
            a, b = i * row + k, (i + 1) * row + k
            if i > 0:
                idx += [a, b, a + 1]
            if i < rings - 1:
                idx += [a + 1, b, b + 1]
    return pos, nrm, idx


def quat_y(theta):
    return (0.0, math.sin(theta / 2), 0.0, math.cos(theta / 2))


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def look_keys(path, target):
    """Camera keys (times, translations, rotations): yaw about +Y then pitch, so the camera's -Z
    points from each position at target."""
    times, tr, rot = [], [], []
    for t, p in path:
        d = [target[i] - p[i] for i in range(3)]
        yaw = math.atan2(-d[0], -d[2])
        pitch = math.atan2(d[1], math.hypot(d[0], d[2]))
        q = quat_mul(quat_y(yaw), (math.sin(pitch / 2), 0.0, 0.0, math.cos(pitch / 2)))
        times.append(t)
        tr.append(tuple(p))
        rot.append(q)
    return times, tr, rot


def cornell_base(shared, keep_cube_anim):
    j, b = read_glb(os.path.join(shared, "peers", "cornell-moving.glb"))
    g = Glb(j, b)
    if not keep_cube_anim:
        g.j["animations"] = []
    cam = [i for i, n in enumerate(g.j["nodes"]) if n.get("camera") is not None][0]
    return g, cam


def flythrough(shared, out):
    g, cam = cornell_base(shared, keep_cube_anim=False)
    # furniture: a pale-yellow sphere and a low blue box, both still
    yellow = g.material("yellow", (0.75, 0.65, 0.25))
    blue = g.material("blue", (0.15, 0.25, 0.6))
    g.node("Sphere", mesh=g.mesh("Sphere", sphere((-0.16, 0.06, 0.16), 0.06), yellow))
    g.node("LowBox", mesh=g.mesh("LowBox", cube((0.17, 0.025, -0.17), (0.07, 0.025, 0.07)), blue))
    path = [(0.0, (-0.10, 0.30, 1.08)), (1.0, (0.02, 0.26, 0.70)), (47 / FPS, (0.10, 0.22, 0.38))]
    times, tr, rot = look_keys(path, (0.0, 0.20, -0.25))
    g.j["nodes"][cam].pop("translation", None)
    g.channels(cam, times, tr, rot)
    g.write(os.path.join(out, "cornell-flythrough.glb"))


def dolly(shared, out):
    g, cam = cornell_base(shared, keep_cube_anim=True)
    path = [(0.0, (-0.08, 0.273, 1.08)), (1.0, (0.0, 0.273, 0.99)), (2.0, (0.08, 0.273, 0.90))]
    times, tr, rot = look_keys(path, (0.0, 0.273, 0.0))
    g.channels(cam, times, tr, rot, anim=0)
    g.write(os.path.join(out, "cornell-dolly.glb"))


def rigged_room(shared, out):
    g, _ = cornell_base(shared, keep_cube_anim=False)
    rj, rb = read_glb(os.path.join(shared, "scenes", "RiggedSimple.glb"))
    # Append RiggedSimple's buffer, views, accessors, materials, meshes, nodes, skins, animation.
    while len(g.bin) % 16:
        g.bin += b"\0"
    boff = len(g.bin)
    g.bin += rb
    vo, ao, mo, meo, no = (len(g.j[k]) for k in ("bufferViews", "accessors", "materials", "meshes", "nodes"))
    so = len(g.j.setdefault("skins", []))
    for v in rj["bufferViews"]:
        g.j["bufferViews"].append(dict(v, buffer=0, byteOffset=v.get("byteOffset", 0) + boff))
    for a in rj["accessors"]:
        g.j["accessors"].append(dict(a, bufferView=a["bufferView"] + vo))
    for m in rj["materials"]:
        m = dict(m, doubleSided=True)
        m["pbrMetallicRoughness"] = dict(m["pbrMetallicRoughness"], metallicFactor=0.0, roughnessFactor=1.0)
        m["extensions"] = {"KHR_materials_specular": {"specularFactor": 0.0}}
        g.j["materials"].append(m)
    for me in rj["meshes"]:
        prims = []
        for p in me["primitives"]:
            p = dict(p, attributes={k: v + ao for k, v in p["attributes"].items()})
            if "indices" in p:
                p["indices"] += ao
            if "material" in p:
                p["material"] += mo
            prims.append(p)
        g.j["meshes"].append(dict(me, primitives=prims))
    for n in rj["nodes"]:
        n = dict(n)
        if "children" in n:
            n["children"] = [c + no for c in n["children"]]
        if "mesh" in n:
            n["mesh"] += meo
        if "skin" in n:
            n["skin"] += so
        g.j["nodes"].append(n)
    for s in rj["skins"]:
        s = dict(s, joints=[x + no for x in s["joints"]])
        if "inverseBindMatrices" in s:
            s["inverseBindMatrices"] += ao
        if "skeleton" in s:
            s["skeleton"] += no
        g.j["skins"].append(s)
    a = rj["animations"][0]
    g.j["animations"] = [{"name": "bend", "samplers": [dict(s, input=s["input"] + ao, output=s["output"] + ao)
                                                         for s in a["samplers"]],
                          "channels": [dict(c, target=dict(c["target"], node=c["target"]["node"] + no))
                                       for c in a["channels"]]}]
    roots = [r + no for r in rj["scenes"][rj.get("scene", 0)]["nodes"]]
    # RiggedSimple stands 9.15 units tall centred on its origin (Z_UP root turns it +Y up).
    s = 0.30 / 9.15
    g.node("Character", children=roots, scale=[s, s, s], translation=[0.12, 4.575 * s + 0.001, -0.10])
    g.write(os.path.join(out, "rigged-room.glb"))


def outdoor(out):
    g = Glb()
    grey = g.material("ground", (0.45, 0.45, 0.42))
    white = g.material("white", (0.8, 0.8, 0.8))
    red = g.material("red", (0.7, 0.12, 0.08))
    blue = g.material("blue", (0.15, 0.3, 0.7))
    s = 100.0
    g.node("Ground", mesh=g.mesh("Ground", ([(-s, 0, -s), (-s, 0, s), (s, 0, s), (s, 0, -s)], [(0, 1, 0)] * 4,
                                            [0, 1, 2, 0, 2, 3]), grey))
    g.node("Block", mesh=g.mesh("Block", cube((-1.2, 0.5, -1.0), (0.5, 0.5, 0.5)), white))
    g.node("Tower", mesh=g.mesh("Tower", cube((1.3, 0.9, -1.4), (0.3, 0.9, 0.3)), red))
    mover = g.node("Mover", mesh=g.mesh("Mover", cube((0, 0, 0), (0.3, 0.3, 0.3)), blue), translation=[-1.5, 0.3, 0.6])
    times = [f / FPS for f in range(FRAMES)]
    tr = [(-1.5 + 3.0 * f / (FRAMES - 1), 0.3, 0.6) for f in range(FRAMES)]
    rot = [quat_y(0.5 * math.pi * f / (FRAMES - 1)) for f in range(FRAMES)]
    g.channels(mover, times, tr, rot)
    # The sun: light travels along the node's -Z; from the upper left, 50 degrees up.
    yaw, pitch = math.radians(-35), math.radians(-50)
    q = quat_mul(quat_y(yaw), (math.sin(pitch / 2), 0.0, 0.0, math.cos(pitch / 2)))
    g.j["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "sun", "type": "directional", "intensity": 3.0, "color": [1.0, 0.96, 0.9]}]}}
    g._ext("KHR_lights_punctual")
    g.node("Sun", rotation=list(q), extensions={"KHR_lights_punctual": {"light": 0}})
    g.j["cameras"] = [{"name": "Camera", "type": "perspective",
                       "perspective": {"aspectRatio": 1.0, "yfov": 0.69, "znear": 0.05, "zfar": 1000.0}}]
    _, tr0, rot0 = look_keys([(0.0, (0.0, 2.6, 5.5))], (0.0, 0.4, -0.4))
    g.node("Camera", camera=0, translation=list(tr0[0]), rotation=list(rot0[0]))
    g.write(os.path.join(out, "outdoor-sun.glb"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--shared", default=os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared"))
    a = ap.parse_args()
    for need in ("peers/cornell-moving.glb", "scenes/RiggedSimple.glb"):
        if not os.path.exists(os.path.join(a.shared, need)):
            sys.exit(f"{os.path.join(a.shared, need)} not found: pass --shared (the folder with peers/ and scenes/)")
    os.makedirs(a.out, exist_ok=True)
    flythrough(a.shared, a.out)
    dolly(a.shared, a.out)
    rigged_room(a.shared, a.out)
    outdoor(a.out)


if __name__ == "__main__":
    main()
