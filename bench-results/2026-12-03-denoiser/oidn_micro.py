# Micro-benchmarks of OIDN's RT filter, CPU seconds of this process (the library chronolux
# links: pyoidn's). Random inputs: the network's cost does not depend on pixel values.
#   oidn_micro.py scale     CPU per call against image size (one filter per size, re-executed)
#   oidn_micro.py quality   CPU per 256x256 call per quality, cleanAux false and true
#   oidn_micro.py threads N CPU per 256x256 call with the device's numThreads = N
#   oidn_micro.py reuse     a new filter per frame (as chronolux) against one kept filter
import sys, time, resource, numpy as np, pyoidn

def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF); return r.ru_utime + r.ru_stime

rng = np.random.default_rng(1)
def images(w, h):
    img = lambda: rng.random((h, w, 3), dtype=np.float32)
    return img(), img(), img() * 2 - 1, np.zeros((h, w, 3), np.float32)

def rt(dev, col, alb, nrm, out, clean=False, quality=None):
    f = pyoidn.Filter(dev, "RT")
    for n, a in [(pyoidn.OIDN_IMAGE_COLOR, col), (pyoidn.OIDN_IMAGE_ALBEDO, alb),
                 (pyoidn.OIDN_IMAGE_NORMAL, nrm), (pyoidn.OIDN_IMAGE_OUTPUT, out)]:
        f.set_image(n, a, pyoidn.OIDN_FORMAT_FLOAT3)
    f.set_bool("hdr", True); f.set_bool("cleanAux", clean)
    if quality is not None: f.set_int("quality", quality)
    f.commit(); return f

def per_call(f, n=4):
    f.execute(); c0, t0 = cpu(), time.time()
    for _ in range(n): f.execute()
    return (cpu() - c0) / n, (time.time() - t0) / n

mode = sys.argv[1]
dev = pyoidn.Device()
if mode == "threads":
    dev.set_int("numThreads", int(sys.argv[2])); dev.set_bool("setAffinity", False)
dev.commit()
if mode == "scale":
    for w, h in [(64, 64), (128, 128), (256, 256), (512, 256), (512, 512), (1024, 1024)]:
        c, t = per_call(rt(dev, *images(w, h)))
        print(f"{w}x{h}: {c*1000:.0f} ms CPU/call, {t*1000:.0f} ms wall, {c/(w*h)*1e9:.0f} ns CPU/pixel")
elif mode == "quality":
    ims = images(256, 256)
    for clean in [False, True]:
        for name, q in [("high", pyoidn.OIDN_QUALITY_HIGH), ("balanced", pyoidn.OIDN_QUALITY_BALANCED), ("fast", pyoidn.OIDN_QUALITY_FAST)]:
            print(f"cleanAux={clean} quality={name}: {per_call(rt(dev, *ims, clean, q))[0]*1000:.0f} ms CPU/call")
elif mode == "threads":
    c, t = per_call(rt(dev, *images(256, 256)), 6)
    print(f"numThreads={sys.argv[2]}: {c*1000:.0f} ms CPU/call, {t*1000:.0f} ms wall")
elif mode == "reuse":
    col0, alb, nrm, out = images(256, 256)
    frames = [images(256, 256)[0] for _ in range(8)]
    for rnd in range(3):
        c0 = cpu()
        for col in frames:
            rt(dev, col, alb, nrm, out).execute()
        c1 = cpu()
        f = pyoidn.Filter(dev, "RT")
        for col in frames:
            for n, a in [(pyoidn.OIDN_IMAGE_COLOR, col), (pyoidn.OIDN_IMAGE_ALBEDO, alb),
                         (pyoidn.OIDN_IMAGE_NORMAL, nrm), (pyoidn.OIDN_IMAGE_OUTPUT, out)]:
                f.set_image(n, a, pyoidn.OIDN_FORMAT_FLOAT3)
            f.set_bool("hdr", True); f.commit(); f.execute()
        print(f"round {rnd}: new filter per frame {(c1-c0)/8*1000:.0f} ms CPU/frame; reused {(cpu()-c1)/8*1000:.0f} ms CPU/frame")
