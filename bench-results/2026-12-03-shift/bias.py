"""Bias check of stbpt's shift: renders A and B (same settings, B with the shift) against
converged references, over the pixels the moving object covers in some frame (where the
reference changes over the frames by more than 5 % of its mean). Prints per frame the
mean signed relative error of A and B there and elsewhere, and relMSE.
usage: bias.py REFDIR ADIR BDIR NFRAMES"""
import sys, numpy as np, OpenEXR, Imath

def load(p):
    f = OpenEXR.InputFile(p)
    dw = f.header()['dataWindow']
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    ch = [np.frombuffer(f.channel(c, Imath.PixelType(Imath.PixelType.FLOAT)), np.float32).reshape(h, w) for c in 'RGB']
    return np.stack(ch, -1).astype(np.float64)

ref, a, b, n = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
R = [load(f'{ref}/frame_{i:04d}.exr') for i in range(n)]
A = [load(f'{a}/frame_{i:04d}.exr') for i in range(n)]
B = [load(f'{b}/frame_{i:04d}.exr') for i in range(n)]
lum = lambda x: x @ np.array([0.2126, 0.7152, 0.0722])
Rl = np.stack([lum(r) for r in R])
mean = Rl.mean(0)
moving = (np.abs(Rl - mean) > 0.05 * (mean + 1e-3)).any(0)
print(f'moving-object pixels: {moving.sum()} of {moving.size}')
tot = {'A': [], 'B': []}
for i in range(n):
    r = Rl[i]
    row = [f'frame {i}']
    for name, X in (('A', A), ('B', B)):
        x = lum(X[i])
        for m, lab in ((moving, 'moving'), (~moving, 'static')):
            row.append(f'{name} {lab} {(x[m].sum() - r[m].sum()) / r[m].sum():+.4f}')
        rel = ((X[i] - R[i]) ** 2 / (R[i] ** 2 + 1e-2)).mean()
        row.append(f'{name} relMSE {rel:.3e}')
        tot[name].append((x[moving].sum() - r[moving].sum()) / r[moving].sum())
    print('  '.join(row))
for k, v in tot.items():
    print(f'{k}: mean signed error over the moving-object pixels {np.mean(v):+.4f}')
