#!/usr/bin/env python3
"""Rooms made at random, to try the per-scene defaults on scenes no rule
was set on (docs/ARCHITECTURE.md, "Per-scene defaults").

Each room is the default scene's five walls and camera with one to three
spheres of radius 0.1 to 0.45 (half of them on the floor) and a light of
radius 0.03 to 0.25 (log-uniform) whose surface lies near the first
sphere: its centre 0.03 to 0.6 (log-uniform) plus its radius from the
sphere's surface. With --anywhere-every-other, every other room has a
light of radius 0.03 to 0.5 anywhere in the room instead, and with
--anywhere every room has. Every light has the default light's power.

    scripts/random_rooms.py OUT_DIR --seed 20261208 --count 20 --prefix sh
    scripts/random_rooms.py OUT_DIR --seed 20261209 --count 24 --prefix rr --anywhere-every-other
"""
import argparse
import math
import os
import random
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
ALBEDOS = [[0.73, 0.73, 0.73], [0.2, 0.4, 0.8], [0.8, 0.6, 0.2], [0.3, 0.7, 0.3], [0.9, 0.9, 0.9], [0.5, 0.2, 0.6]]


def inside(c, r, margin=0.0):
    x, y, z = c
    m = margin
    return -1 + r + m <= x <= 1 - r - m and r + m <= y <= 2 - r - m and -1 + r + m <= z <= 0.9 - r - m


def free(c, r, others, margin=0.02):
    return all(math.dist(c, c2) >= r + r2 + margin for (c2, r2) in others)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out_dir")
    ap.add_argument("--seed", type=int, default=20261208)
    ap.add_argument("--count", type=int, default=20)
    ap.add_argument("--prefix", default="room")
    ap.add_argument("--anywhere-every-other", action="store_true")
    ap.add_argument("--anywhere", action="store_true")
    a = ap.parse_args()
    random.seed(a.seed)
    default = open(os.path.join(ROOT, "scenes", "default.toml")).read()
    walls = "# Walls are" + default.split("# Walls are")[1].split("[[spheres]]")[0]
    os.makedirs(a.out_dir, exist_ok=True)
    k = 0
    while k < a.count:
        n = random.randint(1, 3)
        spheres = []
        tries = 0
        while len(spheres) < n and tries < 1000:
            tries += 1
            r = random.uniform(0.1, 0.45)
            on_floor = random.random() < 0.5
            c = (random.uniform(-1 + r, 1 - r), r if on_floor else random.uniform(r, 2 - r), random.uniform(-1 + r, 0.9 - r))
            if inside(c, r) and free(c, r, spheres):
                spheres.append((c, r))
        lr = math.exp(random.uniform(math.log(0.03), math.log(0.25)))
        gap = math.exp(random.uniform(math.log(0.03), math.log(0.6)))
        sc, sr = spheres[0]
        placed = False
        anywhere = a.anywhere or (a.anywhere_every_other and k % 2 == 1)
        if anywhere:
            lr = math.exp(random.uniform(math.log(0.03), math.log(0.5)))
        for _ in range(200):
            if anywhere:
                lc = (
                    random.uniform(-1 + lr + 0.02, 1 - lr - 0.02),
                    random.uniform(lr + 0.02, 2 - lr - 0.02),
                    random.uniform(-1 + lr + 0.02, 0.9 - lr),
                )
                if free(lc, lr, spheres, 0.02):
                    placed = True
                    break
                continue
            v = [random.gauss(0, 1) for _ in range(3)]
            length = math.sqrt(sum(x * x for x in v))
            v = [x / length for x in v]
            d = sr + gap + lr
            lc = tuple(sc[i] + d * v[i] for i in range(3))
            if inside(lc, lr, 0.02) and free(lc, lr, spheres[1:], 0.02):
                placed = True
                break
        if not placed:
            continue
        radiance = 20.0 * 0.15**2 / lr**2
        g = min(math.dist(lc, c) - r for c, r in spheres)
        spot = 20 / (4 * math.pi * g * g)
        where = "anywhere in the room" if anywhere else "beside the first sphere"
        at = ", ".join(f"{x:.2f}" for x in lc)
        counted = "1 sphere" if n == 1 else f"{n} spheres"
        s = (
            f"# stresses: random room {k}: a light of radius {lr:.3f} {where}, at ({at}), {g:.3f} from the"
            f" nearest sphere (spot {spot:.0f}); {counted}.\n"
        )
        s += f"# Made by scripts/random_rooms.py {' '.join(sys.argv[2:])}.\n\n"
        s += "background = [0.0, 0.0, 0.0]\n\n[camera]\nposition = [0.0, 1.0, 3.4]\nlook_at = [0.0, 1.0, 0.0]\n"
        s += "up = [0.0, 1.0, 0.0]\nvfov_degrees = 40.0\n\n"
        s += "[render]\nwidth = 128\nheight = 128\nspp = 256\nmax_bounces = 5\n\n"
        s += f"[light]\ncenter = [{lc[0]:.4f}, {lc[1]:.4f}, {lc[2]:.4f}]\nradius = {lr:.4f}\n"
        s += f"radiance = [{radiance:.4f}, {radiance:.4f}, {radiance:.4f}]\n\n"
        s += walls
        for i, (c, r) in enumerate(spheres):
            albedo = random.choice(ALBEDOS)
            s += f'[[spheres]]\nname = "sphere {i + 1}"\ncenter = [{c[0]:.4f}, {c[1]:.4f}, {c[2]:.4f}]\n'
            s += f"radius = {r:.4f}\nalbedo = {albedo}\n\n"
        with open(os.path.join(a.out_dir, f"{a.prefix}{k:02d}.toml"), "w") as f:
            f.write(s)
        print(f"{a.prefix}{k:02d} light r={lr:.3f} gap={g:.3f} spot={spot:.0f} spheres={n}")
        k += 1


if __name__ == "__main__":
    main()
