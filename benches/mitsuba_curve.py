"""Mitsuba 3's relMSE against render time on a hexray scene, up to the budget and not short of it.

    python benches/mitsuba_curve.py SCENE.json --ref REF.exr|REF.npy [--res 256] [--seconds 30]
                                    [--integrator path|ptracer] [--spp N] [--seed S]

CSV on stdout, `docs/figures/methods.sh`'s overlay format (scene,variant,spp,seconds,rmse,relmse; the
variant column is the integrator). Each point is a fresh render with its own seed, timed around
the render call alone (after a warm-up render that compiles the kernels), with relMSE = mean
(x - r)^2 / (r^2 + 0.01) over pixel-channels, as `hexray compare` computes it. Waves double the
samples while the next one fits the budget; then one last wave is sized from the measured rate to
end about 15 % past the budget (the rate drifts by up to 10 % from wave to wave), so that the
curve passes the budget and its value there is interpolated between two measurements rather than
read off a wave that ended at half of it.
With --spp N, one render of N samples instead of the curve (for alternating with hexray at
equal time: benches/methods_vs_mitsuba.sh).

The scene goes through ../shared/mitsuba/scene_to_mitsuba.py (MITSUBA_SHARED overrides the
folder); Mitsuba runs its vectorising CPU JIT, llvm_ad_rgb, on all cores. Optional: nothing in the
build or the tests needs it (set-up: ../shared/mitsuba/README.md).
"""
import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.environ.get("MITSUBA_SHARED", os.path.join(HERE, "..", "..", "shared", "mitsuba"))
sys.path.insert(0, SHARED)


def libllvm():
    """Dr.Jit needs an LLVM shared library; Debian's libllvm19 has one."""
    try:
        files = subprocess.run(["dpkg", "-L", "libllvm19"], capture_output=True, text=True).stdout
    except OSError:
        return ""
    return next((p for p in files.split() if "libLLVM.so.19" in p), "")


if not os.environ.get("DRJIT_LIBLLVM_PATH") and libllvm():
    os.environ["DRJIT_LIBLLVM_PATH"] = libllvm()

import numpy as np  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
from scene_to_mitsuba import load_scene  # noqa: E402


def read_reference(path):
    if path.endswith(".npy"):
        return np.load(path).astype(np.float64)[..., :3]
    bitmap = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False)
    return np.array(bitmap, dtype=np.float64)[..., :3]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("--ref", required=True)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--integrator", default="path")
    ap.add_argument("--spp", type=int)
    ap.add_argument("--seed", type=int, default=2000, help="point k renders with seed SEED + spp")
    a = ap.parse_args()

    desc = load_scene(a.scene, res=a.res, spp=1)
    # Unbounded depth with Russian roulette from depth 5, as hexray's methods.
    desc["integrator"] = {"type": a.integrator, "max_depth": -1, "rr_depth": 5, "hide_emitters": False}
    scene = mi.load_dict(desc)
    name = json.load(open(a.scene)).get("name", os.path.splitext(os.path.basename(a.scene))[0])
    reference = read_reference(a.ref)

    def point(spp, show=True):
        start = time.perf_counter()
        x = np.array(mi.render(scene, spp=spp, seed=a.seed + spp), dtype=np.float64)[..., :3]
        seconds = time.perf_counter() - start
        e = (x - reference) ** 2
        if show:
            print(f"{name},{a.integrator},{spp},{seconds:.4f},{np.sqrt(e.mean()):.6g},"
                  f"{(e / (reference ** 2 + 0.01)).mean():.6g}", flush=True)
        return seconds

    point(1, show=False)  # warm-up: compiles the kernels
    print("scene,variant,spp,seconds,rmse,relmse", flush=True)
    if a.spp:
        point(a.spp)
        return
    spp, seconds = 1, point(1)
    while 2 * seconds <= a.seconds:
        spp *= 2
        seconds = point(spp)
    last = int(spp * 1.15 * a.seconds / seconds)
    if last > spp:
        point(last)


if __name__ == "__main__":
    main()
