# Display-space RMSE of L* over the truth's object mask: each image as the PNGs are (ACES, then
# sRGB, 8 bits), L* from its sRGB-decoded luminance. A <model-viewer> screenshot taken with
# tone-mapping="linear" at exposure E is read back to linear and tone-mapped the same way.
#   python3 display_error.py TRUTH.exr TRUTH.png IMAGE.png [--linear-exposure E] ...
import sys, numpy as np, OpenEXR
from PIL import Image
truth_exr, truth_png, rest = sys.argv[1], sys.argv[2], sys.argv[3:]
mask = np.asarray(OpenEXR.File(truth_exr).channels()["RGBA"].pixels)[..., 3] > 0.5
dec = lambda c: np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
enc = lambda c: np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.clip(c, 0, 1) ** (1 / 2.4) - 0.055)
aces = lambda x: np.clip((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0, 1)
def lstar(srgb8):
    lin = dec(srgb8.astype(np.float64) / 255)
    y = 0.2126 * lin[..., 0] + 0.7152 * lin[..., 1] + 0.0722 * lin[..., 2]
    return 116 * np.where(y > (6 / 29) ** 3, np.cbrt(y), y / (3 * (6 / 29) ** 2) + 4 / 29) - 16
png = lambda p: np.asarray(Image.open(p).convert("RGB"))
ref = lstar(png(truth_png))
i = 0
while i < len(rest):
    path, img = rest[i], png(rest[i])
    if i + 2 < len(rest) + 1 and i + 1 < len(rest) and rest[i + 1] == "--linear-exposure":
        lin = dec(img.astype(np.float64) / 255) / float(rest[i + 2])
        img = np.round(enc(aces(np.maximum(lin, 0))) * 255)
        i += 2
    d = (lstar(img) - ref)[mask]
    print(f"{path}: display RMSE L* {np.sqrt((d ** 2).mean()):.3f} over {mask.sum()} pixels")
    i += 1
