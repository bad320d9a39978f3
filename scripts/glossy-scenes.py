#!/usr/bin/env python3
"""Writes the glossy variants of the example scenes (issue 40) into DIR, one per roughness:

  cornell_metal_r<R>.json   the Cornell box with a metal floor (a quad just above the OBJ's
                            floor: base colour 0.9, metallic 1) under its own light
  bunny_glossy_r<R>.json    bunny_sky's bunny as a glossy dielectric (metallic 0) under sky
                            and sun, on a ground of the same roughness
  sphere_metal_r<R>.json    a rough metal sphere (metallic 1) among four small sphere lights
                            on a matte floor
  gradient_metal_r<R>.json  a metal floor under a sky from a black horizon to a white zenith
                            (L = w.y: light the cascades carry, nothing met at a point)

R in 0.1, 0.3, 0.6, 1.0 (the issue's table). Usage: scripts/glossy-scenes.py DIR
"""
import json
import os
import sys

ROUGHNESS = [0.1, 0.3, 0.6, 1.0]
SCENES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "3d")


def cornell(r):
    return {
        "penumbra": 1,
        "dimensions": 3,
        "description": f"The Cornell box with a metal floor of roughness {r} (issue 40)",
        "camera": {"position": [278, 273, -800], "look_at": [278, 273, 0], "up": [0, 1, 0],
                   "fov_y": 39.3, "width": 200, "height": 200},
        "materials": {"metal": {"albedo": [0.9, 0.9, 0.9], "metallic": 1, "roughness": r}},
        "objects": [
            {"type": "mesh", "file": os.path.join(SCENES, "cornell_box.obj")},
            {"type": "quad", "corner": [0, 0.5, 0], "u": [556, 0, 0], "v": [0, 0, 559.2],
             "material": "metal"},
        ],
    }


def bunny(r):
    with open(os.path.join(SCENES, "bunny_sky.json")) as f:
        s = json.load(f)
    s["description"] = f"bunny_sky with a glossy dielectric bunny and ground, roughness {r}"
    s["camera"]["width"], s["camera"]["height"] = 200, 150
    s["materials"]["bunny"].update({"metallic": 0, "roughness": r})
    s["materials"]["ground"].update({"metallic": 0, "roughness": r})
    return s


def sphere(r):
    lights = [([-1.6, 0.5, 0.8], [6, 3, 1]), ([1.5, 0.4, 1.0], [1, 3, 6]),
              ([0.3, 2.3, -0.6], [4, 4, 4]), ([-0.4, 0.25, 1.7], [3, 6, 2])]
    objects = [{"type": "disk", "center": [0, 0, 0], "normal": [0, 1, 0], "radius": 20,
                "material": "floor"},
               {"type": "sphere", "center": [0, 1, 0], "radius": 1, "material": "metal"}]
    materials = {"floor": {"albedo": [0.6, 0.6, 0.6]},
                 "metal": {"albedo": [0.95, 0.8, 0.55], "metallic": 1, "roughness": r}}
    for k, (c, e) in enumerate(lights):
        materials[f"lamp{k}"] = {"emission": e}
        objects.append({"type": "sphere", "center": c, "radius": 0.12, "material": f"lamp{k}"})
    return {
        "penumbra": 1,
        "dimensions": 3,
        "description": f"A rough metal sphere (roughness {r}) among four small sphere lights",
        "camera": {"position": [0, 2.2, 5.5], "look_at": [0, 0.9, 0], "fov_y": 40,
                   "width": 200, "height": 150},
        "materials": materials,
        "objects": objects,
    }


def gradient(r):
    return {
        "penumbra": 1,
        "dimensions": 3,
        "description": f"A metal floor (roughness {r}) under a sky from a black horizon to a "
                       "white zenith",
        "camera": {"position": [0, 2, 4], "look_at": [0, 0, 0], "fov_y": 50,
                   "width": 200, "height": 150},
        "sky": {"zenith": [1, 1, 1], "horizon": [0, 0, 0], "ground": [0, 0, 0]},
        "materials": {"metal": {"albedo": [0.9, 0.9, 0.9], "metallic": 1, "roughness": r}},
        "objects": [{"type": "disk", "center": [0, 0, 0], "normal": [0, 1, 0], "radius": 1000,
                     "material": "metal"}],
    }


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    for r in ROUGHNESS:
        for name, make in (("cornell_metal", cornell), ("bunny_glossy", bunny),
                           ("sphere_metal", sphere), ("gradient_metal", gradient)):
            with open(os.path.join(out, f"{name}_r{r}.json"), "w") as f:
                json.dump(make(r), f, indent=1)
                f.write("\n")


if __name__ == "__main__":
    main()
