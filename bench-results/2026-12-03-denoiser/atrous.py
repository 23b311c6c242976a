# Feasibility: an edge-avoiding a-trous filter (Dammertz 2010 / SVGF-style edge stops) on
# stbpt's noisy frames, against OIDN on the same frames. Writes frame_NNNN.exr to OUT.
import sys, numpy as np, OpenEXR
src, out = sys.argv[1], sys.argv[2]
frames = [int(x) for x in sys.argv[3].split(",")]
sig_n, sig_z, sig_l = float(sys.argv[4]), float(sys.argv[5]), float(sys.argv[6])
iters = int(sys.argv[7])
H = np.array([1/16, 1/4, 3/8, 1/4, 1/16], np.float32)
def shift(a, dy, dx):
    # edge-clamped shift
    h, w = a.shape[:2]
    ys = np.clip(np.arange(h) + dy, 0, h - 1); xs = np.clip(np.arange(w) + dx, 0, w - 1)
    return a[ys][:, xs]
def lum(c): return 0.2126*c[...,0] + 0.7152*c[...,1] + 0.0722*c[...,2]
for fr in frames:
    f = OpenEXR.File(f"{src}/frame_{fr:04d}.exr")
    ch = f.channels()
    noisy = ch["ViewLayer.Noisy Image"].pixels.astype(np.float32)
    alb = ch["ViewLayer.Denoising Albedo"].pixels.astype(np.float32)
    nrm = np.stack([ch[f"ViewLayer.Denoising Normal.{c}"].pixels for c in "XYZ"], -1).astype(np.float32)
    z = ch["ViewLayer.Depth.Z"].pixels.astype(np.float32)
    a = np.maximum(alb, 1e-3)
    valid = (alb.max(-1) > 1e-3)[..., None]
    illum = np.where(valid, noisy / a, noisy)
    L = lum(illum)
    # per-pixel variance estimate: spatial 3x3 variance of luminance
    m1 = sum(shift(L, dy, dx) for dy in (-1,0,1) for dx in (-1,0,1)) / 9
    m2 = sum(shift(L*L, dy, dx) for dy in (-1,0,1) for dx in (-1,0,1)) / 9
    var = np.maximum(m2 - m1*m1, 0)
    c = illum
    for it in range(iters):
        step = 1 << it
        acc = np.zeros_like(c); wacc = np.zeros(c.shape[:2], np.float32)
        vacc = np.zeros_like(var)
        Lc = lum(c)
        # prefiltered variance (3x3 gaussian) for the luminance stop
        vg = sum(shift(var, dy, dx) * H[dy+2]*H[dx+2]*(16/6)*(16/6)/ (1) for dy in (-1,0,1) for dx in (-1,0,1))
        vg = vg / sum(H[dy+2]*H[dx+2]*(16/6)*(16/6) for dy in (-1,0,1) for dx in (-1,0,1))
        sd = np.sqrt(vg) + 1e-6
        for dy in range(-2, 3):
            for dx in range(-2, 3):
                k = H[dy+2]*H[dx+2]
                qy, qx = dy*step, dx*step
                cq = shift(c, qy, qx); nq = shift(nrm, qy, qx); zq = shift(z, qy, qx); Lq = shift(Lc, qy, qx)
                wn = np.maximum(0, (nrm*nq).sum(-1)) ** sig_n
                wz = np.exp(-np.abs(z - zq) / (sig_z * np.maximum(z, 1e-3) * step * max(abs(dy), abs(dx), 1) + 1e-6))
                wl = np.exp(-np.abs(Lc - Lq) / (sig_l * sd)) if sig_l > 0 else 1.0
                w = k * wn * wz * wl
                acc += w[..., None] * cq; wacc += w
                vacc += (w*w) * shift(var, qy, qx)
        c = acc / np.maximum(wacc, 1e-12)[..., None]
        var = vacc / np.maximum(wacc*wacc, 1e-24)
    res = np.where(valid, c * a, c).astype(np.float32)
    OpenEXR.File({"type": OpenEXR.scanlineimage, "compression": OpenEXR.ZIP_COMPRESSION},
                 {"RGB": res}).write(f"{out}/frame_{fr:04d}.exr")
