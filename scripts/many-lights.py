#!/usr/bin/env python3
"""The scenes of docs/PERFORMANCE.md's check that the cost does not grow with the lights.

A floor before a wall and a patch of small spheres on the floor, of which only some emit: the
geometry is the same whatever the count, so the time says what the lights cost.
  patch_N.json   20 x 10 spheres of radius 0.12, 0.5 and 0.9 apart, N = 2 or 200 emitting, 640x360
  carpet_N.json  50 x 40 spheres of radius 0.04, 0.1 apart, N = 2, 20, 200 or 2000 emitting (drawn
                 at random, seed 1), 320x180

    python3 scripts/many-lights.py OUT_DIR
"""
import json
import os
import random
import sys


def scene(width, height, spheres, lit):
    objects = [
        {"type": "quad", "corner": [-10, 0, -10], "u": [0, 0, 20], "v": [20, 0, 0], "material": "floor"},
        {"type": "quad", "corner": [-10, 0, -6], "u": [20, 0, 0], "v": [0, 4, 0], "material": "floor"},
    ]
    for k, (centre, radius) in enumerate(spheres):
        material = "lamp" if k in lit else "ball"
        objects.append({"type": "sphere", "center": centre, "radius": radius, "material": material})
    return {
        "penumbra": 1,
        "dimensions": 3,
        "camera": {"position": [0, 3, 7], "look_at": [0, 0, -1], "fov_y": 50, "width": width, "height": height},
        "materials": {
            "floor": {"albedo": [0.6, 0.6, 0.6]},
            "ball": {"albedo": [0.7, 0.7, 0.7]},
            "lamp": {"emission": [5, 4, 3]},
        },
        "objects": objects,
    }


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    patch = [([round(-4.75 + 0.5 * i, 4), 0.15, round(-5 + 0.9 * j, 4)], 0.12) for i in range(20) for j in range(10)]
    for n in (2, 200):
        with open(os.path.join(out, f"patch_{n}.json"), "w") as f:
            json.dump(scene(640, 360, patch, set(range(n))), f)
    carpet = [([round(-4.75 + 0.1 * i, 4), 0.15, round(-5 + 0.1 * j, 4)], 0.04) for i in range(50) for j in range(40)]
    order = list(range(len(carpet)))
    random.Random(1).shuffle(order)
    for n in (2, 20, 200, 2000):
        with open(os.path.join(out, f"carpet_{n}.json"), "w") as f:
            json.dump(scene(320, 180, carpet, set(order[:n])), f)


if __name__ == "__main__":
    main()
