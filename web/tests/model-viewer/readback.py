# The linear radiance of a <model-viewer> screenshot taken with tone-mapping="linear" at
# exposure E (sRGB-decoded, divided by E), as an OpenEXR with the truth's alpha as the object
# mask, for `oslf compare`: python3 readback.py SHOT.png E TRUTH.exr OUT.exr
import sys, numpy as np, OpenEXR
from PIL import Image
shot, exposure, truth, out = sys.argv[1], float(sys.argv[2]), sys.argv[3], sys.argv[4]
t = np.asarray(OpenEXR.File(truth).channels()["RGBA"].pixels, dtype=np.float32)
c = np.asarray(Image.open(shot).convert("RGB")).astype(np.float32) / 255
if (c >= 254.5 / 255).any():
    sys.exit(f"{shot}: clipped pixels; lower the exposure")
lin = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4) / exposure
rgba = np.concatenate([lin, t[..., 3:4]], -1).astype(np.float32)
OpenEXR.File({"type": OpenEXR.scanlineimage, "compression": OpenEXR.ZIP_COMPRESSION}, {"RGBA": rgba}).write(out)
print(out, "max", float(lin.max()))
