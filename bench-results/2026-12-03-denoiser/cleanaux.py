# OIDN's RT filter on the noisy frames of atrous.sh's stbpt render (layers of out-d2), in
# variants written as DIR/frame_NNNN.exr for `chronolux compare`:
#   py-default      cleanAux false, quality high (what chronolux does: the same images)
#   py-cleanaux     OIDN's parameter cleanAux set true
#   py-clean_aux    the oidn crate's parameter name "clean_aux" set true (OIDN ignores it)
#   py-clean-fast, py-clean-balanced, py-noisy-fast: cleanAux and quality combined
# Usage: python cleanaux.py out-d2 0,1,2,3,4,5,6,7,12   (run in atrous.sh's folder)
import sys, os, numpy as np, OpenEXR, pyoidn
src, frames = sys.argv[1], [int(x) for x in sys.argv[2].split(",")]
dev = pyoidn.Device(); dev.commit()
Q = {"high": pyoidn.OIDN_QUALITY_HIGH, "balanced": pyoidn.OIDN_QUALITY_BALANCED, "fast": pyoidn.OIDN_QUALITY_FAST}
VARIANTS = {
    "py-default": ({}, "high"), "py-cleanaux": ({"cleanAux": True}, "high"),
    "py-clean_aux": ({"clean_aux": True}, "high"), "py-clean-fast": ({"cleanAux": True}, "fast"),
    "py-clean-balanced": ({"cleanAux": True}, "balanced"), "py-noisy-fast": ({}, "fast"),
}
for name in VARIANTS: os.makedirs(name, exist_ok=True)
for fr in frames:
    ch = OpenEXR.File(f"{src}/frame_{fr:04d}.exr").channels()
    col = np.ascontiguousarray(ch["ViewLayer.Noisy Image"].pixels.astype(np.float32))
    alb = np.ascontiguousarray(ch["ViewLayer.Denoising Albedo"].pixels.astype(np.float32))
    nrm = np.ascontiguousarray(np.stack([ch[f"ViewLayer.Denoising Normal.{c}"].pixels for c in "XYZ"], -1).astype(np.float32))
    for name, (flags, q) in VARIANTS.items():
        out = np.zeros_like(col); f = pyoidn.Filter(dev, "RT")
        for n, a in [(pyoidn.OIDN_IMAGE_COLOR, col), (pyoidn.OIDN_IMAGE_ALBEDO, alb), (pyoidn.OIDN_IMAGE_NORMAL, nrm), (pyoidn.OIDN_IMAGE_OUTPUT, out)]:
            f.set_image(n, a, pyoidn.OIDN_FORMAT_FLOAT3)
        f.set_bool("hdr", True); f.set_int("quality", Q[q])
        for k, v in flags.items(): f.set_bool(k, v)
        f.commit(); f.execute(); f.release()
        OpenEXR.File({"type": OpenEXR.scanlineimage, "compression": OpenEXR.ZIP_COMPRESSION}, {"RGB": out}).write(f"{name}/frame_{fr:04d}.exr")
