import sys, numpy as np, mitsuba as mi
mi.set_variant("scalar_rgb")
ref = np.load(sys.argv[1]).astype(np.float64)
def relmse(img, ref, b):
    h, w = ref.shape[0] // b, ref.shape[1] // b
    a = img[:h*b, :w*b, :3].reshape(h, b, w, b, 3).mean(axis=(1, 3))
    r = ref[:h*b, :w*b, :3].reshape(h, b, w, b, 3).mean(axis=(1, 3))
    return float(np.mean((a - r) ** 2 / (r ** 2 + 1e-2)))
for path in sys.argv[2:]:
    img = np.array(mi.Bitmap(path), dtype=np.float64)
    print(path, " ".join("%.4e" % relmse(img, ref, b) for b in (1, 2, 4, 8)))
