import os, sys, numpy as np
# World-space triangles of cornell-moving at frame 0 as Mitsuba builds them (peer harness),
# 9 little-endian f32 per triangle, to tris.bin next to this file.
HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "../../../scripts/peer")
sys.path.insert(0, os.path.join(HERE, "harness"))
os.environ.setdefault("DRJIT_CACHE_DIR", os.path.join(HERE, ".drjit-cache"))
import peer_mitsuba as pm
pm.pick_libllvm()
r = pm.MitsubaAnim("llvm_ad_rgb", "/work/shared/peers/cornell-moving.glb")
r.set_time(0.0)
out=[]
for s in r.scene.shapes():
    if not hasattr(s, "vertex_positions_buffer"): continue
    v = np.array(s.vertex_positions_buffer()).reshape(-1,3)
    f = np.array(s.faces_buffer()).reshape(-1,3)
    out.append(v[f].reshape(-1,9))
    print(s.id(), v.shape, f.shape)
t=np.concatenate(out).astype("<f4"); t.tofile(os.path.join(os.path.dirname(os.path.abspath(__file__)), "tris.bin")); print(t.shape)
