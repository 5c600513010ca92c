#!/usr/bin/env python3
"""Renders one of our TOML scenes with Mitsuba 3, as an independent check.

Not part of CI. Needs `pip install mitsuba` and Debian's `libllvm19` for the
`llvm_ad_rgb` variant; DRJIT_LIBLLVM_PATH defaults to Debian's library.

The translation is exact for what our scenes contain:
- walls: `rectangle` shapes mapped onto corner + [0,1]^2 (edge_u, edge_v),
  with a `twosided` diffuse BSDF (Mitsuba's diffuse is one-sided);
- spheres: `sphere` shapes with a diffuse BSDF;
- the light: a `sphere` with an `area` emitter and a black diffuse BSDF
  (it reflects nothing);
- the camera: `perspective`, vertical field of view, box pixel filter
  (our jittered samples are a box filter);
- `path` integrator with max_depth = max_bounces + 1 (Mitsuba counts path
  vertices, we count scattering events); Russian roulette is unbiased in both.

Usage: render.py SCENE.toml OUT.exr [--width W] [--height H] [--spp N]
       [--max-bounces N] [--seed S] [--time-only]
Prints the render time (after a warm-up render that compiles the kernels).
"""

import argparse
import os
import sys
import time
import tomllib

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1")

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")
from mitsuba import ScalarTransform4f as T  # noqa: E402


def rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def diffuse(albedo, twosided=False):
    bsdf = {"type": "diffuse", "reflectance": rgb(albedo)}
    return {"type": "twosided", "bsdf": bsdf} if twosided else bsdf


def wall_transform(corner, eu, ev):
    # Mitsuba's rectangle spans [-1, 1]^2 in the xy plane, normal +z.
    n = [eu[1] * ev[2] - eu[2] * ev[1], eu[2] * ev[0] - eu[0] * ev[2], eu[0] * ev[1] - eu[1] * ev[0]]
    ln = sum(x * x for x in n) ** 0.5
    n = [x / ln for x in n]
    c = [corner[i] + 0.5 * eu[i] + 0.5 * ev[i] for i in range(3)]
    m = [
        [0.5 * eu[0], 0.5 * ev[0], n[0], c[0]],
        [0.5 * eu[1], 0.5 * ev[1], n[1], c[1]],
        [0.5 * eu[2], 0.5 * ev[2], n[2], c[2]],
        [0.0, 0.0, 0.0, 1.0],
    ]
    return T(m)


def scene_dict(scene, width, height, max_bounces, spp, seed, sampler="independent"):
    cam = scene["camera"]
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_bounces + 1, "hide_emitters": False},
        "sensor": {
            "type": "perspective",
            "fov": float(cam["vfov_degrees"]),
            "fov_axis": "y",
            "to_world": T().look_at(origin=cam["position"], target=cam["look_at"], up=cam.get("up", [0, 1, 0])),
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": sampler, "sample_count": spp, "seed": seed},
        },
    }
    bg = scene.get("background", [0, 0, 0])
    if any(x > 0 for x in bg):
        d["background"] = {"type": "constant", "radiance": rgb(bg)}
    light = scene["light"]
    d["light"] = {
        "type": "sphere",
        "center": light["center"],
        "radius": float(light["radius"]),
        "bsdf": diffuse([0, 0, 0]),
        "emitter": {"type": "area", "radiance": rgb(light["radiance"])},
    }
    for i, w in enumerate(scene.get("walls", [])):
        d[f"wall{i}"] = {
            "type": "rectangle",
            "to_world": wall_transform(w["corner"], w["edge_u"], w["edge_v"]),
            "bsdf": diffuse(w["albedo"], twosided=True),
        }
    for i, s in enumerate(scene.get("spheres", [])):
        d[f"sphere{i}"] = {
            "type": "sphere",
            "center": s["center"],
            "radius": float(s["radius"]),
            "bsdf": diffuse(s["albedo"]),
        }
    return d


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--width", type=int, default=256)
    ap.add_argument("--height", type=int, default=256)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--max-bounces", type=int, default=5)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--passes", type=int, default=1, help="independent passes of --spp each, averaged")
    args = ap.parse_args()
    with open(args.scene, "rb") as f:
        scene = tomllib.load(f)
    d = scene_dict(scene, args.width, args.height, args.max_bounces, args.spp, args.seed)
    s = mi.load_dict(d)
    # Warm-up: compiles the kernels, not timed.
    mi.render(s, spp=1, seed=args.seed + 100000)
    start = time.perf_counter()
    acc = None
    for p in range(args.passes):
        img = mi.render(s, spp=args.spp, seed=args.seed + p)
        arr = mi.TensorXf(img)
        acc = arr if acc is None else acc + arr
    img = acc / args.passes
    dr.eval(img)
    dr.sync_thread()
    elapsed = time.perf_counter() - start
    mi.Bitmap(img).write(args.out)
    total = args.width * args.height * args.spp * args.passes
    print(f"mitsuba {mi.__version__} llvm_ad_rgb: {elapsed:.3f} s, {total / elapsed:.3e} samples/s, wrote {args.out}")


if __name__ == "__main__":
    sys.exit(main())
