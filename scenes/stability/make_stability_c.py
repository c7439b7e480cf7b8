#!/usr/bin/env python3
"""Writes the caustic and tiny-light stability scenes (run from anywhere; the JSON is committed).

caustic.json: a glass sphere (ior 1.5) under a small downward-facing light, above a white
diffuse floor, with nothing else in the world. The floor under the sphere sees the light only
through the glass: shadow rays toward the light hit the sphere, so next-event estimation finds
nothing there, and the focused light (the caustic) is found only by BSDF sampling, by diffuse
floor paths that happen to refract through the sphere onto the light.

tiny_light_1e2.json, tiny_light_1e4.json: tncg15_room with its 2x2 ceiling light shrunk about its
centre to 1/100 and 1/10000 of the area, radiance scaled up by the same factor so its power (and
the direct light far from it) stays nearly the same. Next-event estimation keeps direct light
clean at any size; paths diffuse -> mirror -> light, which only BSDF sampling finds, get rarer
and brighter as the light shrinks (fireflies in the mirror sphere's and mirror wall's
reflections of the light).
"""
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))
TNCG15 = os.path.join(HERE, "..", "tncg15_room.json")


def square(cx, cy, z, half, material, part, down=True):
    """Two triangles of the square [cx-half, cx+half] x [cy-half, cy+half] at height z, wound to
    face -z (down) or +z."""
    a = [cx - half, cy - half, z]
    b = [cx + half, cy - half, z]
    c = [cx + half, cy + half, z]
    d = [cx - half, cy + half, z]
    if down:
        return [{"v": [a, c, b], "material": material, "part": part},
                {"v": [a, d, c], "material": material, "part": part}]
    return [{"v": [a, b, c], "material": material, "part": part},
            {"v": [a, c, d], "material": material, "part": part}]


def caustic():
    return {
        "name": "caustic",
        "seed": "scenes/stability/make_stability_c.py: a glass sphere focusing a small light onto a diffuse floor",
        "notes": ["the floor under the sphere is lit only through the glass: light that only BSDF sampling finds"],
        "camera": {"eye": [0.0, -4.0, 3.0], "look_at": [0.0, 0.0, 0.3], "up": [0, 0, 1], "vfov_deg": 45.0,
                   "note": "looking down at the floor around the sphere; +x is image right"},
        "materials": {
            "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]},
            "glass": {"type": "glass", "ior": 1.5},
            "light": {"type": "emitter", "radiance": [200.0, 200.0, 200.0]},
        },
        "triangles": square(0.0, 0.0, 0.0, 5.0, "floor", "floor", down=False)
        + square(0.0, 0.0, 4.0, 0.15, "light", "light", down=True),
        "spheres": [{"center": [0.0, 0.0, 1.2], "radius": 1.0, "material": "glass"}],
    }


def tiny_light(base, factor, label):
    """tncg15_room with the light's area divided by `factor` about its centre and its radiance
    multiplied by `factor`."""
    scene = json.loads(json.dumps(base))
    scene["name"] = f"tiny_light_{label}"
    scene["seed"] = f"tncg15_room.json with the light's area / {label} and radiance x {label} (make_stability_c.py)"
    shrink = factor ** -0.5
    lights = [t for t in scene["triangles"] if t["material"] == "light"]
    pts = [v for t in lights for v in t["v"]]
    centre = [sum(p[k] for p in pts) / len(pts) for k in range(3)]
    for t in lights:
        t["v"] = [[centre[k] + shrink * (v[k] - centre[k]) for k in range(3)] for v in t["v"]]
    le = scene["materials"]["light"]["radiance"]
    scene["materials"]["light"]["radiance"] = [x * factor for x in le]
    return scene


def write(name, scene):
    path = os.path.join(HERE, name)
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")
    print(path)


def main():
    write("caustic.json", caustic())
    with open(TNCG15) as f:
        base = json.load(f)
    write("tiny_light_1e2.json", tiny_light(base, 1e2, "1e2"))
    write("tiny_light_1e4.json", tiny_light(base, 1e4, "1e4"))


if __name__ == "__main__":
    main()
