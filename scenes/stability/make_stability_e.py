#!/usr/bin/env python3
"""Writes the failure-atlas scenes of this folder (run from anywhere; the JSON files are
committed). Each is a small scene where one family of light-transport methods fails and another
succeeds; docs/atlas.sh renders every method on them against a 32x32 reference
(tests/data/references/stability/, made by docs/figures/stability.sh references).

door_ajar.json: Veach's door ajar. A closed enclosure 6 x 3 x 2.5 (x in [-3, 3], y in
  [-1.5, 1.5], z in [0, 2.5]), diffuse albedo 0.7, split at x = 0 by a zero-thickness diffuse
  wall with a doorway (y in [0.3, 1.1], z in [0, 2]). The door (a diffuse quad, 0.8 x 2) is
  hinged at y = 0.3 and opened 10 degrees into the lit room (x > 0): the light passes a slit 0.139
  wide between its free edge and the jamb. A 0.5 x 0.8 emitter (Le = 250, facing down) on the lit
  room's ceiling beside the doorway (x in [0.05, 0.55], y in [0.6, 1.4]) is the only light. The
  camera is in the dark room (x < 0) near the dividing wall, looking away from it: it sees no
  emitter and no part of the slit. Next-event estimation from the dark room is occluded almost
  everywhere (only a streak of floor lit through the slit is direct), so path tracing must find
  the slit by BSDF sampling; light subpaths start beside the slit, pass it as rarely as camera
  paths do, and every vertex beyond it connects to the camera.

mirror_caustic.json: a caustic seen only in a mirror. A glass sphere (ior 1.5, radius 0.8,
  centre height 2) under a small emitter (0.2 x 0.2 at height 5, Le = 500, facing down) focuses it
  onto a diffuse floor (albedo 0.8) at the sphere's foot: for a ball lens f = n r / (2 (n - 1)) =
  1.2 from the centre, the light 3 from it images 2 below it, on the floor. A diffuse wall 0.7
  high at y = -1 hides the floor for y < 1.6 from the camera (at (0, -4, 1.5)), and a planar
  mirror (reflectance 0.9) at y = 3, facing -y, shows it: the camera sees the caustic only in the
  mirror, under the sphere. Paths camera -> mirror -> floor -> glass -> glass -> light:
  specular-diffuse-specular. Light tracing cannot reach the camera through the mirror (those
  pixels stay black in hexray's `light`); a connection from a light vertex on the floor to a
  camera vertex on the floor has zero cosine; path tracing and BDPT have only BSDF sampling
  through the sphere onto the small light; photon merging at the floor vertex finds the caustic.

enclosed_light.json: a light bulb. A small emitting sphere (radius 0.06, Le = 200) inside a
  glass shell (outer radius 0.25, inner 0.22, ior 1.5: a glass sphere with a flipped-normal glass
  sphere, a bubble of air, inside it), hanging at (0, 0, 1.9) in a diffuse room 4 x 4 x 2.5
  (white albedo 0.7, a red wall at x = -2 and a green wall at x = 2, and a white block on the
  floor). Every shadow ray toward the emitter hits the glass, so next-event estimation finds
  nothing and all the light in the room is a caustic of the glass shell (the shell barely
  deflects it: the room looks lit as if the glass were not there). Path tracing must hit the
  small emitter by BSDF sampling; light tracing and BDPT's light subpaths leave the bulb through
  the glass and connect to the camera from the first diffuse vertex on.
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))

# The quads and rectangles of make_stability_a.py, whose scenes are written only when it runs as a script.
from make_stability_a import quad, x_rect, y_rect, z_rect  # noqa: E402


def r6(p):
    return [round(x, 6) for x in p]


DOOR_DEG = 10.0


def door_ajar():
    hy0, hy1, dz = 0.3, 1.1, 2.0  # doorway y range and height
    w = hy1 - hy0
    t = math.radians(DOOR_DEG)
    edge = [w * math.sin(t), hy0 + w * math.cos(t)]  # the door's free edge (x, y)
    slit = math.hypot(edge[0], hy1 - edge[1])
    tris = []
    tris += x_rect(0.0, -1.5, hy0, 0.0, 2.5, "wall", "dividing wall, left of the doorway", +1)
    tris += x_rect(0.0, hy1, 1.5, 0.0, 2.5, "wall", "dividing wall, right of the doorway", +1)
    tris += x_rect(0.0, hy0, hy1, dz, 2.5, "wall", "dividing wall, lintel", +1)
    a, b = [0.0, hy0, 0.0], r6([edge[0], edge[1], 0.0])
    c, d = r6([edge[0], edge[1], dz]), [0.0, hy0, dz]
    tris += quad(a, b, c, d, "wall", f"door, hinged at y = {hy0}, open {DOOR_DEG:g} degrees into x > 0")
    tris += z_rect(2.49, 0.05, 0.55, 0.6, 1.4, "light", "emitter on the lit room's ceiling, facing down", -1)
    return {
        "name": "door_ajar",
        "seed": "scenes/stability/make_stability_e.py: Veach's door ajar, a dark room lit through"
                " a slit from a lit neighbouring room",
        "notes": [
            "stresses next-event estimation: from the dark room (x < 0) the light is occluded"
            " almost everywhere; light enters only through the slit of the door ajar",
            f"enclosure x in [-3, 3], y in [-1.5, 1.5], z in [0, 2.5] (a `boxes` entry, diffuse"
            f" 0.7); dividing wall x = 0 with a doorway y in [{hy0}, {hy1}], z in [0, {dz}]",
            f"door 0.8 x 2 hinged at (0, {hy0}), open {DOOR_DEG:g} degrees into the lit room:"
            f" slit {slit:.3f} wide between its free edge and the jamb",
            "emitter 0.5 x 0.8, Le = 250, on the lit room's ceiling beside the doorway, facing"
            " down; the camera sees neither it nor the slit",
            "path tracing must find the slit by BSDF sampling; light subpaths find it as often"
            " and connect to the camera (light, bdpt, vcm)",
        ],
        "camera": {"eye": [-0.4, -1.0, 1.6], "look_at": [-3.0, 0.4, 0.7], "up": [0, 0, 1],
                   "vfov_deg": 70.0,
                   "note": "in the dark room by the dividing wall, looking away from the door"},
        "materials": {
            "wall": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]},
            "light": {"type": "emitter", "radiance": [250.0, 250.0, 250.0]},
        },
        "triangles": tris,
        "boxes": [{"min": [-3.0, -1.5, 0.0], "max": [3.0, 1.5, 2.5], "material": "wall"}],
    }


def mirror_caustic():
    tris = []
    tris += z_rect(0.0, -5.0, 5.0, -5.0, 3.0, "floor", "floor", +1)
    tris += z_rect(5.0, -0.1, 0.1, -0.1, 0.1, "light", "emitter 0.2 x 0.2 facing down", -1)
    tris += y_rect(3.0, -3.0, 3.0, 0.0, 2.5, "mirror", "mirror y = 3 facing -y", -1)
    tris += y_rect(-1.0, -3.0, 3.0, 0.0, 0.7, "wall", "occluder y = -1, 0.7 high", -1)
    return {
        "name": "mirror_caustic",
        "seed": "scenes/stability/make_stability_e.py: a glass sphere's caustic that the camera"
                " sees only in a planar mirror",
        "notes": [
            "stresses specular-diffuse-specular paths: camera -> mirror -> floor -> glass ->"
            " light",
            "glass sphere ior 1.5, radius 0.8, centre (0, 0, 2); emitter 0.2 x 0.2 at z = 5,"
            " Le = 500, facing down: the ball lens images it onto the floor at (0, 0, 0)",
            "floor z = 0 (albedo 0.8); occluder y = -1, 0.7 high, hides the floor for y < 1.6;"
            " mirror y = 3 (reflectance 0.9) facing -y shows it",
            "light tracing cannot reach the camera through the mirror; light-vertex to"
            " camera-vertex connections on the floor have zero cosine; photon merging at the floor"
            " finds the caustic",
        ],
        "camera": {"eye": [0.0, -4.0, 1.5], "look_at": [0.0, 3.0, 0.5], "up": [0, 0, 1],
                   "vfov_deg": 40.0,
                   "note": "over the occluder at the mirror; +x is image right"},
        "materials": {
            "floor": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]},
            "wall": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
            "mirror": {"type": "mirror", "reflectance": [0.9, 0.9, 0.9]},
            "glass": {"type": "glass", "ior": 1.5},
            "light": {"type": "emitter", "radiance": [500.0, 500.0, 500.0]},
        },
        "triangles": tris,
        "spheres": [{"center": [0.0, 0.0, 2.0], "radius": 0.8, "material": "glass"}],
    }


def enclosed_light():
    c = [0.0, 0.0, 1.9]
    tris = []
    tris += x_rect(-1.999, -2.0, 2.0, 0.0, 2.5, "red", "red wall x = -2", +1)
    tris += x_rect(1.999, -2.0, 2.0, 0.0, 2.5, "green", "green wall x = 2", -1)
    return {
        "name": "enclosed_light",
        "seed": "scenes/stability/make_stability_e.py: a small light inside a glass shell (a"
                " bulb) lighting a diffuse room",
        "notes": [
            "stresses next-event estimation: every shadow ray toward the emitter hits the glass,"
            " so all the room's light is a caustic of the shell",
            "emitter sphere radius 0.06, Le = 200, inside a glass shell (outer radius 0.25,"
            " inner 0.22, ior 1.5: a flipped-normal glass sphere is the air inside), centre"
            " (0, 0, 1.9)",
            "room x, y in [-2, 2], z in [0, 2.5] (a `boxes` entry, diffuse 0.7); red wall"
            " x = -2, green wall x = 2 (just inside the box); white block on the floor",
            "path tracing must hit the small emitter by BSDF sampling; light subpaths leave the"
            " bulb and connect to the camera (light, bdpt, vcm)",
        ],
        "camera": {"eye": [0.0, -1.95, 1.2], "look_at": [0.0, 0.0, 1.0], "up": [0, 0, 1],
                   "vfov_deg": 80.0,
                   "note": "at the room's front wall looking in; +x is image right"},
        "materials": {
            "white": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]},
            "red": {"type": "diffuse", "albedo": [0.63, 0.065, 0.05]},
            "green": {"type": "diffuse", "albedo": [0.14, 0.45, 0.091]},
            "glass": {"type": "glass", "ior": 1.5},
            "light": {"type": "emitter", "radiance": [200.0, 200.0, 200.0]},
        },
        "triangles": tris,
        "spheres": [
            {"center": c, "radius": 0.25, "material": "glass"},
            {"center": c, "radius": 0.22, "material": "glass", "flip_normals": True},
            {"center": c, "radius": 0.06, "material": "light"},
        ],
        "boxes": [
            {"min": [-2.0, -2.0, 0.0], "max": [2.0, 2.0, 2.5], "material": "white"},
            {"min": [0.3, 0.2, 0.0], "max": [1.0, 0.9, 0.8], "material": "white"},
        ],
    }


def write(name, scene):
    path = os.path.join(HERE, name)
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")
    print(path)


def main():
    write("door_ajar.json", door_ajar())
    write("mirror_caustic.json", mirror_caustic())
    write("enclosed_light.json", enclosed_light())


if __name__ == "__main__":
    main()
