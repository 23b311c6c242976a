import sys, numpy as np, OpenEXR
src, layer, out = sys.argv[1], sys.argv[2], sys.argv[3]
for fr in [int(x) for x in sys.argv[4].split(",")]:
    ch = OpenEXR.File(f"{src}/frame_{fr:04d}.exr").channels()
    OpenEXR.File({"type": OpenEXR.scanlineimage, "compression": OpenEXR.ZIP_COMPRESSION},
                 {"RGB": ch[layer].pixels.astype(np.float32)}).write(f"{out}/frame_{fr:04d}.exr")
