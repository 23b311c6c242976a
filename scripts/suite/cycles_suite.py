#!/usr/bin/env python3
"""Blender Cycles 5 (bpy, CPU) on a suite scene, with the peers harness's settings
(../shared/peers/harness/peer_cycles.py: Blender's own glTF importer, fixed spp, box filter,
6 bounces = Mitsuba max_depth 8, no clamping, OIDN with albedo + normal and the accurate
prefilter, black world). Run with the peers venv's Python (it needs bpy):

  cycles_suite.py check SCENE.glb
      what the importer made next to the glTF: materials, lights, and for frames 0, 12, 24, 47
      the largest distance between Blender's and the glTF's world position of every mesh and
      camera node (and the camera's view direction), so a frame-offset or axis mistake shows
  cycles_suite.py ref SCENE.glb --res R --frames 0,1,24 --spp 512 --pass-spp 64 --out DIR
      Cycles' own converged reference of those frames: DIR/frame_NNNN.exr (+ _A/_B halves),
      DIR/ref.json with the CPU seconds and the halves' remaining relMSE per frame
  cycles_suite.py ttf SCENE.glb --res R --frames 0,1,24 --levels 1,2,4 --refs DIR --denoise
      CPU seconds (user + sys of this process around each frame's render call: scene sync,
      denoise and EXR writing included; the glTF import is not) of the scored frames at each
      spp level (animated seed), mean HDR-FLIP and flicker against DIR (harness metrics), and
      the log-log interpolation to each --targets FLIP ([value, "=" | "<=" | "not reached"]);
      one JSON object on stdout.

The sun of a scene (KHR_lights_punctual directional) is given the glTF intensity as its
strength in W/m^2 and angle 0 (a delta light), which is what Chronolux does with it (the
glTF intensity times the colour as irradiance); Blender's importer would divide by 683.
"""
import argparse
import json
import os
import sys
import tempfile

HARNESS = os.environ.get("PEER_HARNESS", os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                      "..", "..", "..", "shared", "peers", "harness"))
sys.path.insert(0, HARNESS)
try:
    import numpy as np
    import peer_cycles as pc
    from exr_io import read_exr, write_exr
    from metrics import flip_mean, save_cache
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from suite_metrics import flicker, interp
except ImportError as e:
    sys.exit(f"cycles_suite.py: {e}. Run it with the peers venv: python3 -m venv /work/.venv-peers && "
             f"/work/.venv-peers/bin/pip install -r {HARNESS}/requirements.txt (PEER_HARNESS: the harness folder)")


def frames_of(s):
    return pc.parse_frames(s)


def gltf_lights(path):
    from gltf_scene import GltfScene
    g = GltfScene(path).g
    ext = (g.extensions or {}).get("KHR_lights_punctual", {})
    return ext.get("lights", [])


def setup(scene, res, spp, denoise=False):
    import bpy
    pc.SCENE, pc.RES = scene, res
    sc = pc.setup(spp, denoise=denoise)
    lights = gltf_lights(scene)
    for ob in sc.objects:
        if ob.type == "LIGHT" and ob.data.type == "SUN":
            src = [l for l in lights if l.get("type") == "directional"]
            if len(src) != 1:
                sys.exit(f"{scene}: {len(src)} directional lights in the glTF, this driver maps exactly one")
            ob.data.energy = float(src[0].get("intensity", 1.0))
            ob.data.color = tuple(src[0].get("color", [1, 1, 1]))
            ob.data.angle = 0.0
        elif ob.type == "LIGHT":
            sys.exit(f"{scene}: light {ob.name} of type {ob.data.type}: this driver maps only suns")
    return sc


def cmd_check(a):
    import bpy
    from gltf_scene import GltfScene
    sc = setup(a.scene, a.res, 4)
    print("blender", bpy.app.version_string, "frames", sc.frame_start, sc.frame_end, "fps", sc.render.fps)
    for m in bpy.data.materials:
        b = [n for n in m.node_tree.nodes if n.type == "BSDF_PRINCIPLED"] if m.use_nodes else []
        if b:
            b = b[0]
            print(f"material {m.name}: base {tuple(round(x, 4) for x in b.inputs['Base Color'].default_value[:3])}"
                  f" metal {b.inputs['Metallic'].default_value:.2f} specIORlevel {b.inputs['Specular IOR Level'].default_value:.2f}"
                  f" emission {tuple(round(x, 3) for x in b.inputs['Emission Color'].default_value[:3])}"
                  f" x {b.inputs['Emission Strength'].default_value:.3f}")
    for ob in sc.objects:
        if ob.type == "LIGHT":
            print(f"light {ob.name}: {ob.data.type} energy {ob.data.energy} colour {tuple(ob.data.color)} angle {getattr(ob.data, 'angle', None)}")
    gs = GltfScene(a.scene)
    names = {n.name: i for i, n in enumerate(gs.g.nodes) if n.name and (n.mesh is not None or n.camera is not None)}
    worst = 0.0
    for fr in [0, 12, 24, 47]:
        sc.frame_set(fr)
        W = gs.world_matrices(fr / 24.0)
        line = []
        for name, ni in names.items():
            ob = bpy.data.objects.get(name)
            if ob is None or gs.g.nodes[ni].skin is not None:
                continue
            pb = np.array(ob.matrix_world.translation)
            pb = np.array([pb[0], pb[2], -pb[1]])
            d = float(np.linalg.norm(pb - W[ni][:3, 3]))
            if gs.g.nodes[ni].camera is not None:
                fb = np.array(ob.matrix_world.to_3x3() @ __import__("mathutils").Vector((0, 0, -1)))
                fb = np.array([fb[0], fb[2], -fb[1]])
                fg = W[ni][:3, :3] @ np.array([0, 0, -1.0])
                fg /= np.linalg.norm(fg)
                line.append(f"camera {name} pos diff {d:.2e} view-direction diff {np.linalg.norm(fb - fg):.2e}")
                d = max(d, float(np.linalg.norm(fb - fg)))
            worst = max(worst, d)
        print(f"frame {fr}: " + "; ".join(line))
    print(f"largest position/direction difference over mesh and camera nodes, frames 0/12/24/47: {worst:.2e}")
    sk = [o for o in sc.objects if o.type == "ARMATURE"]
    if sk:
        ob = [o for o in sc.objects if o.type == "MESH" and any(m.type == "ARMATURE" for m in o.modifiers)][0]
        for fr in [0, 24, 47]:
            sc.frame_set(fr)
            dg = bpy.context.evaluated_depsgraph_get()
            me = ob.evaluated_get(dg).to_mesh()
            P = np.array([ob.matrix_world @ v.co for v in me.vertices])
            print(f"frame {fr}: skinned mesh {ob.name} bounds (glTF axes) min {np.round(P.min(0)[[0, 2, 1]] * [1, 1, -1], 4)} "
                  f"max {np.round(P.max(0)[[0, 2, 1]] * [1, 1, -1], 4)}")


def cmd_ref(a):
    sc = setup(a.scene, a.res, a.pass_spp)
    sc.cycles.use_animated_seed = False
    npass = a.spp // a.pass_spp
    if npass < 2 or npass % 2:
        sys.exit("--spp must be an even multiple (>= 2) of --pass-spp")
    os.makedirs(a.out, exist_ok=True)
    tmp = os.path.join(tempfile.mkdtemp(), "pass.exr")
    info = {"spp": a.spp, "pass_spp": a.pass_spp, "res": a.res, "scene": a.scene, "frames": {}}
    for fr in frames_of(a.frames):
        c0 = pc.cpu_s()
        halves = [np.zeros((a.res, a.res, 3)), np.zeros((a.res, a.res, 3))]
        for p in range(npass):
            sc.cycles.seed = 100000 + 1000 * fr + p
            pc.render_frame(sc, fr, tmp)
            halves[p % 2] += read_exr(tmp)
        halves = [h / (npass // 2) for h in halves]
        ref = 0.5 * (halves[0] + halves[1])
        write_exr(os.path.join(a.out, f"frame_{fr:04d}.exr"), ref)
        write_exr(os.path.join(a.out, f"frame_{fr:04d}_A.exr"), halves[0], half=True)
        write_exr(os.path.join(a.out, f"frame_{fr:04d}_B.exr"), halves[1], half=True)
        rel = float(np.mean(((halves[0] - halves[1]) / 2) ** 2 / (ref ** 2 + 0.01)))
        info["frames"][fr] = {"cpu_s": pc.cpu_s() - c0, "relmse_estimate": rel, "mean": float(ref.mean())}
        print(json.dumps({"frame": fr, **info["frames"][fr]}), file=sys.stderr, flush=True)
    json.dump(info, open(os.path.join(a.out, "ref.json"), "w"), indent=1)


def cmd_ttf(a):
    FR = frames_of(a.frames)
    refs = [read_exr(os.path.join(a.refs, f"frame_{f:04d}.exr")).astype(np.float64) for f in FR]
    tmp = tempfile.mkdtemp()
    levels = []
    for spp in [int(s) for s in a.levels.split(",")]:
        sc = setup(a.scene, a.res, spp, denoise=a.denoise)
        imgs, cpu = [], 0.0
        for f in FR:
            p = os.path.join(tmp, f"f{f:04d}_s{spp}.exr")
            _, c = pc.render_frame(sc, f, p)
            cpu += c
            imgs.append(read_exr(p).astype(np.float64)[..., :3])
        fl = float(np.mean([flip_mean(refs[k], imgs[k]) for k in range(len(FR))]))
        levels.append({"spp": spp, "cpu_s": cpu, "flip": fl, "flicker": flicker(imgs, refs, FR)})
        print(json.dumps(levels[-1]), file=sys.stderr, flush=True)
        if a.keep:
            os.makedirs(a.keep, exist_ok=True)
            for f, im in zip(FR, imgs):
                write_exr(os.path.join(a.keep, f"spp{spp}_frame_{f:04d}.exr"), im, half=True)
    save_cache()
    out = {"renderer": "cycles", "denoise": a.denoise, "frames": FR, "res": a.res, "levels": levels,
           "interp_cpu_s": {}, "flicker_at": {}}
    for t in [float(x) for x in a.targets.split(",")]:
        out["interp_cpu_s"][str(t)] = interp(levels, t)
        out["flicker_at"][str(t)] = interp(levels, t, "flicker")[0]
    print(json.dumps(out))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cmd", choices=["check", "ref", "ttf"])
    ap.add_argument("scene")
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--frames", default="0")
    ap.add_argument("--spp", type=int, default=512)
    ap.add_argument("--pass-spp", type=int, default=64)
    ap.add_argument("--out")
    ap.add_argument("--refs")
    ap.add_argument("--levels", default="1,2,4,8,16")
    ap.add_argument("--targets", default="0.08,0.05")
    ap.add_argument("--denoise", action="store_true")
    ap.add_argument("--keep", help="also write the ttf frames (half float) here")
    a = ap.parse_args()
    if not os.path.exists(a.scene):
        sys.exit(f"{a.scene}: no such scene file")
    a.scene = os.path.abspath(a.scene)
    {"check": cmd_check, "ref": cmd_ref, "ttf": cmd_ttf}[a.cmd](a)


if __name__ == "__main__":
    main()
