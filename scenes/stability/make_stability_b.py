#!/usr/bin/env python3
"""Writes the scenes of the stability tests' second part (run from anywhere; the JSON files are
committed). Every scene is `scenes/tncg15_room.json` changed in one way, in the existing format:

far from the origin (tests/stability_far_from_origin.rs)
  tncg15_translated_1eK.json, K = 3..7: every point (vertices, sphere centres, the camera's eye
      and look_at) moved by (t, t, t), t = 10^K, i.e. along (1, 1, 1). The image is unchanged in
      exact arithmetic. 1e6 and 1e7 are where f32 fails (see the test's header); the tests
      render 1e3, 1e4 and 1e5.
  tncg15_scaled_1e-3.json, tncg15_scaled_1e3.json: every point and radius multiplied by s about
      the origin. Radiance is scale-free (the rendering equation has no length in it once
      emitted radiance and albedos are fixed), so the image is unchanged too.

mirror (tests/stability_mirror.rs), by the method of images
  tncg15_mirror_doubled.json: the room without its mirror wall EF (the plane y = -6), plus the
      room's reflection across that plane (every triangle, the sphere, the tetrahedron and the
      light; two vertices of each reflected triangle swapped so that the light still faces
      down), with the camera still in the original room. A mirror of reflectance 1 is an
      opening into the mirror-image world, so this renders tncg15_room's image exactly.
  tncg15_mirror_tinted.json: tncg15_room with the mirror wall's reflectance r = TINT (the sphere
      keeps reflectance 1: it gets its own material).
  tncg15_doubled_tinted_window.json: the doubled room with a window in the opening: two
      triangles of glass with index 1 and tint r. Glass of index 1 has Fresnel reflectance 0 and
      refracts straight through with weight = tint, so every crossing of the plane multiplies a
      path by r, as every bounce off the mirror of reflectance r does: the same image again.

shadow colour (tests/stability_shadow_colour.rs)
  tncg15_umbra_view.json: tncg15_room with the camera moved between the tetrahedron and the red
      wall, looking at the tetrahedron's face y = 4 (which no point of the light can see: the
      light is behind its plane) and at the floor strip in its cast shadow.

The script checks the geometry it relies on: nothing of the room straddles the mirror plane,
and the doubled room is closed (every edge of its non-emitting triangles is shared by exactly
two of them).
"""
import copy
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))
ROOM = os.path.join(HERE, "..", "tncg15_room.json")
MIRROR_Y = -6.0
TINT = [0.9, 0.6, 0.3]


def load_room():
    with open(ROOM) as f:
        return json.load(f)


def write(name, data):
    with open(os.path.join(HERE, name + ".json"), "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")


def map_points(room, f, radius=lambda r: r):
    """A copy of the room with f applied to every point and `radius` to every radius."""
    s = copy.deepcopy(room)
    for t in s["triangles"]:
        t["v"] = [f(v) for v in t["v"]]
    for sp in s["spheres"]:
        sp["center"] = f(sp["center"])
        sp["radius"] = radius(sp["radius"])
    s["camera"]["eye"] = f(s["camera"]["eye"])
    s["camera"]["look_at"] = f(s["camera"]["look_at"])
    s["camera"].pop("note", None)
    return s


def translated(room, k):
    t = 10.0 ** k
    s = map_points(room, lambda p: [x + t for x in p])
    s["name"] = f"tncg15_translated_1e{k}"
    s["seed"] = f"tncg15_room with every point moved by ({t:g}, {t:g}, {t:g})"
    return s


def scaled(room, k):
    f = 10.0 ** k
    s = map_points(room, lambda p: [x * f for x in p], lambda r: r * f)
    s["name"] = f"tncg15_scaled_1e{k}"
    s["seed"] = f"tncg15_room with every point and radius multiplied by {f:g} about the origin"
    return s


def reflect(p):
    return [p[0], 2.0 * MIRROR_Y - p[1], p[2]]


def is_mirror_wall(t):
    return t["part"] == "wall EF"


def check_mirror_wall(room):
    walls = [t for t in room["triangles"] if is_mirror_wall(t)]
    assert len(walls) == 2 and all(t["material"] == "mirror" for t in walls)
    assert all(v[1] == MIRROR_Y for t in walls for v in t["v"])
    # Nothing else straddles (or pokes through) the mirror plane: the room is on the side y >= -6.
    for t in room["triangles"]:
        assert all(v[1] >= MIRROR_Y for v in t["v"]), t
    for sp in room["spheres"]:
        assert sp["center"][1] - sp["radius"] > MIRROR_Y, sp
    assert room["camera"]["eye"][1] > MIRROR_Y


def edge_counts(triangles):
    counts = {}
    for t in triangles:
        v = [tuple(p) for p in t["v"]]
        for a, b in ((v[0], v[1]), (v[1], v[2]), (v[2], v[0])):
            e = (min(a, b), max(a, b))
            counts[e] = counts.get(e, 0) + 1
    return counts


def doubled(room, window=None):
    s = copy.deepcopy(room)
    s["camera"].pop("note", None)
    kept = [t for t in room["triangles"] if not is_mirror_wall(t)]
    images = []
    for t in kept:
        v0, v1, v2 = (reflect(p) for p in t["v"])
        # A reflection reverses orientation; swapping two vertices restores the reflected normal.
        images.append({"v": [v0, v2, v1], "material": t["material"],
                       "part": t["part"] + " (mirror image)"})
    s["triangles"] = kept + images
    s["spheres"] = room["spheres"] + [
        {"center": reflect(sp["center"]), "radius": sp["radius"], "material": sp["material"]}
        for sp in room["spheres"]
    ]
    # Closed: every edge of the non-emitting triangles (walls, floor, ceiling, tetrahedra) is
    # shared by exactly two triangles, so the opening is exactly the removed mirror wall.
    counts = edge_counts([t for t in s["triangles"] if t["material"] != "light"])
    assert all(c == 2 for c in counts.values()), [e for e, c in counts.items() if c != 2]
    # Each image lies entirely on the far side of the plane.
    assert all(v[1] <= MIRROR_Y for t in images for v in t["v"])
    if window is not None:
        s["triangles"] += window
    return s


def main():
    room = load_room()
    check_mirror_wall(room)

    for k in (3, 4, 5, 6, 7):
        write(f"tncg15_translated_1e{k}", translated(room, k))
    for k in (-3, 3):
        write(f"tncg15_scaled_1e{k}", scaled(room, k))

    d = doubled(room)
    d["name"] = "tncg15_mirror_doubled"
    d["seed"] = ("tncg15_room without its mirror wall, plus the room's reflection across the "
                 "mirror plane y = -6 (method of images: equals tncg15_room)")
    write("tncg15_mirror_doubled", d)

    tinted = copy.deepcopy(room)
    tinted["camera"].pop("note", None)
    tinted["materials"]["wall_mirror"] = {"type": "mirror", "reflectance": TINT}
    for t in tinted["triangles"]:
        if is_mirror_wall(t):
            t["material"] = "wall_mirror"
    tinted["name"] = "tncg15_mirror_tinted"
    tinted["seed"] = f"tncg15_room with the mirror wall's reflectance {TINT} (the sphere keeps 1)"
    write("tncg15_mirror_tinted", tinted)

    window = [dict(t, material="window", part="window (glass of index 1, tint r)")
              for t in room["triangles"] if is_mirror_wall(t)]
    w = doubled(room, window)
    w["materials"]["window"] = {"type": "glass", "ior": 1.0, "tint": TINT}
    w["name"] = "tncg15_doubled_tinted_window"
    w["seed"] = ("tncg15_mirror_doubled with a window of glass of index 1 and tint "
                 f"{TINT} in the opening (equals tncg15_mirror_tinted)")
    write("tncg15_doubled_tinted_window", w)

    u = copy.deepcopy(room)
    u["camera"] = {
        "eye": [8.3, 5.9, -3.9],
        "look_at": [8.3, 4.0, -4.5],
        "up": [0.0, 0.0, 1.0],
        "vfov_deg": 70.0,
        "note": "between the tetrahedron and the red wall, looking at the tetrahedron's unlit "
                "face y = 4 and the floor strip in its shadow",
    }
    u["name"] = "tncg15_umbra_view"
    u["seed"] = "tncg15_room seen from between the tetrahedron and the red wall"
    write("tncg15_umbra_view", u)


main()
