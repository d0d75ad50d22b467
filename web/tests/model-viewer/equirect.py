# The store's environment cube (six face EXRs from `oslf store export-cube --layout faces`) as an
# equirectangular Radiance .hdr in three.js's convention (model-viewer's environment-image),
# for a glTF (Y-up) placed in a Z-up scene by a +90 degree rotation about x.
import sys, numpy as np, OpenEXR
prefix, out = sys.argv[1], sys.argv[2]
W, H = 1024, 512
faces = []
for name in ["px", "nx", "py", "ny", "pz", "nz"]:
    f = OpenEXR.File(f"{prefix}_{name}.exr")
    ch = f.channels()
    if "RGB" in ch:
        rgb = np.asarray(ch["RGB"].pixels, dtype=np.float32)
    elif "RGBA" in ch:
        rgb = np.asarray(ch["RGBA"].pixels, dtype=np.float32)[..., :3]
    else:
        rgb = np.stack([np.asarray(ch[c].pixels, dtype=np.float32) for c in "RGB"], -1)
    faces.append(rgb)
n = faces[0].shape[0]
i, j = np.meshgrid(np.arange(W), np.arange(H))
u = (i + 0.5) / W
v = 1.0 - (j + 0.5) / H
phi = (u - 0.5) * 2 * np.pi
theta = (v - 0.5) * np.pi
gx, gy, gz = np.cos(theta) * np.cos(phi), np.sin(theta), np.cos(theta) * np.sin(phi)
# glTF -> scene: (x, -z, y)
x, y, z = gx, -gz, gy
ax, ay, az = np.abs(x), np.abs(y), np.abs(z)
face = np.where((ax >= ay) & (ax >= az), np.where(x >= 0, 0, 1), np.where(ay >= az, np.where(y >= 0, 2, 3), np.where(z >= 0, 4, 5)))
sc = np.select([face == 0, face == 1, face == 2, face == 3, face == 4, face == 5], [-z, z, x, x, x, -x])
tc = np.select([face == 0, face == 1, face == 2, face == 3, face == 4, face == 5], [-y, -y, z, -z, -y, -y])
ma = np.select([face <= 1, face <= 3, face <= 5], [ax, ay, az])
s = (sc / ma + 1) / 2
t = (tc / ma + 1) / 2
# bilinear within the face
fx = np.clip(s * n - 0.5, 0, n - 1)
fy = np.clip(t * n - 0.5, 0, n - 1)
x0 = np.floor(fx).astype(int); y0 = np.floor(fy).astype(int)
x1 = np.minimum(x0 + 1, n - 1); y1 = np.minimum(y0 + 1, n - 1)
wx = (fx - x0)[..., None]; wy = (fy - y0)[..., None]
stack = np.stack(faces)
def at(yy, xx): return stack[face, yy, xx]
img = (at(y0, x0) * (1 - wx) + at(y0, x1) * wx) * (1 - wy) + (at(y1, x0) * (1 - wx) + at(y1, x1) * wx) * wy
img = np.maximum(img, 0)
# RGBE
m = img.max(-1)
e = np.where(m > 1e-32, np.floor(np.log2(np.maximum(m, 1e-32))) + 1, -128)
scale = np.where(m > 1e-32, 256.0 / np.exp2(e), 0)
rgbe = np.zeros((H, W, 4), np.uint8)
rgbe[..., :3] = np.clip(img * scale[..., None], 0, 255).astype(np.uint8)
rgbe[..., 3] = np.where(m > 1e-32, e + 128, 0).astype(np.uint8)
with open(out, "wb") as f:
    f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {H} +X {W}\n".encode())
    f.write(rgbe.tobytes())
print(out, img.shape, "max", float(img.max()), "mean", float(img.mean()))
