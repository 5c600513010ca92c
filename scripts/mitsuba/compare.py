#!/usr/bin/env python3
"""Mitsuba 3's error against time on one of our scenes, for `pathtracer bench`.

Renders the scene with Mitsuba 3 (llvm_ad_rgb, `path` integrator, max_depth =
max_bounces + 1, box filter; see render.py for the translation) at 4, 8, ...,
MAX spp and writes `time_s,rel_mse` (median time, mean relMSE over seeds) against REFERENCE.exr,
which `pathtracer bench convergence` writes (our CPU renderer, 100x the
largest budget).

Fairness:
- Mitsuba's kernels are compiled before timing: each sample count is rendered
  once untimed (same scene, other seed), then timed; Dr.Jit caches the kernel.
- Both renderers get the same machine, scene, camera, resolution, bounce
  limit, pixel filter, and one sample stream per pixel per sample count;
  Mitsuba renders each count from scratch (it has no progressive mode), so
  its time at N spp is one N-spp render, while ours accumulates.
- relMSE is the project's (docs/ARCHITECTURE.md, Conventions): mean((I - R)^2 / (R^2 + 0.01)) per pixel and
  channel.

Usage: compare.py SCENE.toml REFERENCE.exr OUT.csv [--max-spp 1024] [--seeds 3]
"""

import argparse
import os
import sys
import time
import tomllib

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("llvm_ad_rgb")
from render import scene_dict  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("reference")
    ap.add_argument("out")
    ap.add_argument("--max-spp", type=int, default=1024)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--max-bounces", type=int, default=5)
    args = ap.parse_args()

    ref = np.array(mi.Bitmap(args.reference), dtype=np.float64)[:, :, :3]
    height, width = ref.shape[0], ref.shape[1]
    with open(args.scene, "rb") as f:
        scene = tomllib.load(f)
    s = mi.load_dict(scene_dict(scene, width, height, args.max_bounces, 4, 0))

    rows = []
    spp = 4
    while spp <= args.max_spp:
        mi.render(s, spp=spp, seed=999_999)  # compile for this count, untimed
        times, errors = [], []
        for seed in range(args.seeds):
            start = time.perf_counter()
            img = mi.render(s, spp=spp, seed=seed)
            dr.eval(img)
            dr.sync_thread()
            times.append(time.perf_counter() - start)
            a = np.array(img, dtype=np.float64)[:, :, :3]
            errors.append(float(np.mean((a - ref) ** 2 / (ref**2 + 0.01))))
        rows.append((float(np.median(times)), float(np.mean(errors)), spp))
        print(f"mitsuba {spp} spp: {rows[-1][0]:.4f} s, relMSE {rows[-1][1]:.4e}", file=sys.stderr)
        spp *= 2
    with open(args.out, "w") as f:
        f.write("time_s,rel_mse,spp\n")
        for t, e, n in rows:
            f.write(f"{t:.6f},{e:.6e},{n}\n")


if __name__ == "__main__":
    sys.exit(main())
