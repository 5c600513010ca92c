#!/usr/bin/env python3
"""Mitsuba 3's error against time on our scenes, for `pathtracer bench`.

Renders a scene with Mitsuba 3 (llvm_ad_rgb, `path` integrator, max_depth =
max_bounces + 1, box filter; see render.py for the translation) at 4, 8, ...
spp with each of its samplers -- independent, multijitter, ldsampler and
orthogonal -- and measures relMSE against a reference that
`pathtracer bench` writes (our CPU renderer, far more samples).

Two modes:
- one scene: `compare.py SCENE.toml REFERENCE.exr OUT.csv` writes
  `time_s,rel_mse,spp` (median time, mean relMSE over seeds) of the sampler
  that reaches relMSE 1e-3 soonest, and names it on stderr;
- the suite: `compare.py --suite SUITE.tsv OUT_DIR` reads the list that
  `pathtracer bench convergence --suite --reference-only` writes and writes
  OUT_DIR/<scene>.csv with `sampler,seed,spp,time_s,rel_mse` for every
  sampler, seed and sample count; the bench reads each seed's time to the
  target along its own curve, as it does ours. It also writes
  OUT_DIR/<scene>.exr, a 1024-spp render for the agreement check.

Fairness:
- Mitsuba's kernels are compiled before timing: each sampler and sample
  count is rendered once untimed (same scene, other seed), then timed;
  Dr.Jit caches the kernel.
- Both renderers get the same machine, scene, camera, resolution, bounce
  limit, pixel filter and reference. Mitsuba renders each count from
  scratch (it has no progressive mode), so its time at N spp is one N-spp
  render; `pathtracer bench` times ours the same way.
- A sampler may round the sample count (multijitter and orthogonal need
  squares or prime powers); the count Mitsuba reports is the one written.
- relMSE is the project's (docs/ARCHITECTURE.md, Conventions):
  mean((I - R)^2 / (R^2 + 0.01)) per pixel and channel.
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

SAMPLERS = ["independent", "multijitter", "ldsampler", "orthogonal"]


def curves(scene, ref, max_bounces, seeds, max_spp, target, samplers, label):
    """Rows (sampler, seed, spp, time_s, rel_mse); a sampler stops after the
    first count at which every seed's relMSE is below `target`."""
    height, width = ref.shape[0], ref.shape[1]
    rows = []
    for sampler in samplers:
        spp = 4
        while spp <= max_spp:
            s = mi.load_dict(scene_dict(scene, width, height, max_bounces, spp, 0, sampler))
            actual = s.sensors()[0].sampler().sample_count()
            mi.render(s, seed=999_999)  # compile for this count, untimed
            errors = []
            for seed in range(seeds):
                start = time.perf_counter()
                img = mi.render(s, seed=seed)
                dr.eval(img)
                dr.sync_thread()
                elapsed = time.perf_counter() - start
                a = np.array(img, dtype=np.float64)[:, :, :3]
                errors.append(float(np.mean((a - ref) ** 2 / (ref**2 + 0.01))))
                rows.append((sampler, seed, actual, elapsed, errors[-1]))
            print(f"{label}: mitsuba {sampler} {actual} spp: relMSE {np.mean(errors):.3e}", file=sys.stderr)
            if max(errors) < target:
                break
            spp = max(spp * 2, actual + 1)
    return rows


def load(scene_path):
    with open(scene_path, "rb") as f:
        return tomllib.load(f)


def reference(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]


def time_to(curve, target):
    """log-log interpolation of the time at which relMSE reaches target."""
    for (t0, e0), (t1, e1) in zip(curve, curve[1:]):
        if e0 >= target >= e1:
            f = (np.log(target) - np.log(e0)) / (np.log(e1) - np.log(e0))
            return float(np.exp(np.log(t0) + f * (np.log(t1) - np.log(t0))))
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("inputs", nargs="+", help="SCENE.toml REFERENCE.exr OUT.csv, or with --suite: SUITE.tsv OUT_DIR")
    ap.add_argument("--suite", action="store_true")
    ap.add_argument("--max-spp", type=int, default=8192)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--target", type=float, default=1e-3)
    ap.add_argument("--max-bounces", type=int, default=None, help="default: the scene's, else 5")
    ap.add_argument("--samplers", default=",".join(SAMPLERS))
    ap.add_argument("--check-spp", type=int, default=1024, help="--suite: spp of each scene's agreement image")
    args = ap.parse_args()
    samplers = args.samplers.split(",")

    if args.suite:
        if len(args.inputs) != 2:
            ap.error("--suite takes SUITE.tsv OUT_DIR")
        tsv, out_dir = args.inputs
        os.makedirs(out_dir, exist_ok=True)
        with open(tsv) as f:
            lines = f.read().splitlines()[1:]
        for line in lines:
            name, scene_path, ref_path, _w, _h, max_bounces, ref_noise = line.split("\t")
            ref = reference(ref_path)
            # relMSE against the reference includes the reference's own,
            # which the bench takes off: stop where the bench's target is.
            target = args.target + float(ref_noise)
            rows = curves(load(scene_path), ref, int(max_bounces), args.seeds, args.max_spp, target, samplers, name)
            with open(os.path.join(out_dir, f"{name}.csv"), "w") as f:
                f.write("sampler,seed,spp,time_s,rel_mse\n")
                for r in rows:
                    f.write(f"{r[0]},{r[1]},{r[2]},{r[3]:.6f},{r[4]:.6e}\n")
            # An image for the agreement check (`pathtracer compare --max-t`
            # against the reference): independent samples, so that its
            # pixels' errors are independent and the t test's stderr holds.
            s = mi.load_dict(scene_dict(load(scene_path), ref.shape[1], ref.shape[0], int(max_bounces),
                                        args.check_spp, 7, "independent"))
            mi.Bitmap(mi.render(s, seed=7)).write(os.path.join(out_dir, f"{name}.exr"))
        return 0

    if len(args.inputs) != 3:
        ap.error("expected SCENE.toml REFERENCE.exr OUT.csv")
    scene_path, ref_path, out = args.inputs
    scene = load(scene_path)
    max_bounces = args.max_bounces or scene.get("render", {}).get("max_bounces", 5)
    # One curve per sampler, run to 1024 spp so that each covers the range of ours.
    rows = curves(scene, reference(ref_path), max_bounces, args.seeds, 1024, 0.0, samplers, scene_path)
    best = None
    for sampler in samplers:
        pts = []
        for spp in sorted({r[2] for r in rows if r[0] == sampler}):
            at = [r for r in rows if r[0] == sampler and r[2] == spp]
            pts.append((float(np.median([r[3] for r in at])), float(np.mean([r[4] for r in at])), spp))
        t = time_to([(p[0], p[1]) for p in pts], args.target)
        print(f"mitsuba {sampler}: time to relMSE {args.target:.0e}: {t}", file=sys.stderr)
        if t is not None and (best is None or t < best[0]):
            best = (t, sampler, pts)
    if best is None:
        sys.exit("no sampler reached the target")
    print(f"mitsuba's fastest sampler: {best[1]}", file=sys.stderr)
    with open(out, "w") as f:
        f.write(f"time_s,rel_mse,spp,{best[1]}\n")
        for t, e, n in best[2]:
            f.write(f"{t:.6f},{e:.6e},{n}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
