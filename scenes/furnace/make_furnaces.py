#!/usr/bin/env python3
"""Writes the furnace scenes of this folder (run from anywhere; the JSON files are committed).

A furnace is a closed cube [-1, 1]^3 whose twelve triangles face inward and both emit
Le = 1 - rho and reflect diffusely with albedo rho. Whatever a path does inside, the radiance
it sees satisfies L = Le + rho L, so L = 1 exactly everywhere (the rendering equation's
solution for a uniform closed enclosure). Mirror and glass spheres of unit reflectance and tint
inside change nothing: the image must still be exactly 1.
"""
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def inward_cube():
    tris = []
    c = lambda k: [(-1.0, 1.0)[k & 1], (-1.0, 1.0)[(k >> 1) & 1], (-1.0, 1.0)[(k >> 2) & 1]]
    # Each face as a quad, counter-clockwise seen from INSIDE, so (v1-v0)x(v2-v0) points in.
    faces = [[0, 2, 6, 4], [1, 5, 7, 3], [0, 4, 5, 1], [2, 3, 7, 6], [0, 1, 3, 2], [4, 6, 7, 5]]
    names = ["-x", "+x", "-y", "+y", "-z", "+z"]
    for q, name in zip(faces, names):
        for a, b, d in ((q[0], q[1], q[2]), (q[0], q[2], q[3])):
            tris.append({"v": [c(a), c(b), c(d)], "material": "wall", "part": f"wall {name}"})
    return tris


def scene(name, rho, spheres, note):
    return {
        "name": name,
        "seed": note,
        "notes": [
            "closed cube of inward-facing emitters with albedo rho and radiance 1 - rho: "
            "the exact image is 1 in every pixel and channel"
        ],
        "camera": {"eye": [-0.5, 0.0, 0.0], "look_at": [1.0, 0.0, 0.0], "up": [0, 0, 1],
                   "vfov_deg": 90.0},
        "materials": {
            "wall": {"type": "emitter", "radiance": [1 - rho] * 3, "albedo": [rho] * 3},
            "mirror": {"type": "mirror", "reflectance": [1.0, 1.0, 1.0]},
            "glass": {"type": "glass", "ior": 1.5, "tint": [1.0, 1.0, 1.0]},
        },
        "triangles": inward_cube(),
        "spheres": spheres,
    }


def write(name, data):
    with open(os.path.join(HERE, name + ".json"), "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")


for rho, tag in ((0.5, "0_5"), (0.8, "0_8"), (0.95, "0_95")):
    write(f"diffuse_{tag}", scene(f"furnace_diffuse_{tag}", rho, [],
                                   f"white furnace, albedo {rho}"))
# The merging furnace: the inside of a sphere of radius 1 (normals flipped inward) that emits
# Le = 1 - rho and reflects with albedo rho, seen from its centre. Besides L = 1, a sphere has the
# property photon merging needs to be exact: the surface within chord distance r of any point on
# it is a cap of area exactly pi r^2 (Archimedes: a cap of height h has area 2 pi R h, and chord
# r gives h = r^2 / 2R), so a disk kernel's normalisation is exact at every radius.
sphere = scene("furnace_sphere", 0.5, [], "white furnace inside a sphere, albedo 0.5")
sphere["notes"] = [
    "inside of an emitting sphere with albedo rho and radiance 1 - rho: the exact image is 1, "
    "and the area within chord distance r of any surface point is exactly pi r^2"
]
sphere["camera"]["eye"] = [0.0, 0.0, 0.0]
sphere["triangles"] = []
sphere["spheres"] = [
    {"center": [0.0, 0.0, 0.0], "radius": 1.0, "material": "wall", "flip_normals": True}
]
write("sphere", sphere)
write("mirror_sphere", scene("furnace_mirror_sphere", 0.5,
                             [{"center": [0.4, 0.0, 0.0], "radius": 0.45, "material": "mirror"}],
                             "mirror sphere of reflectance 1 in a furnace"))
write("glass_sphere", scene("furnace_glass_sphere", 0.5,
                            [{"center": [0.4, 0.0, 0.0], "radius": 0.45, "material": "glass"}],
                            "glass sphere of index 1.5 and tint 1 in a furnace"))
# The black furnace: walls that emit 1 and reflect nothing, with a mirror sphere and a glass
# sphere (tint 1). Every wall is 1, straight or in the spheres, so any method that follows
# mirrors and glass without loss sees 1 everywhere: Whitted ray tracing's specular transport
# against an exact answer (tests/whitted.rs), where the diffuse furnaces' indirect light is
# what Whitted leaves out.
write("black_specular", scene("furnace_black_specular", 0.0,
                              [{"center": [0.4, -0.45, 0.0], "radius": 0.35, "material": "mirror"},
                               {"center": [0.4, 0.45, 0.0], "radius": 0.35, "material": "glass"}],
                              "mirror and glass spheres in a furnace of black emitters"))
