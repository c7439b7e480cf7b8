#!/usr/bin/env python3
"""Writes the stability scenes of this folder that tests/stability_mirror_corridor.rs,
tests/stability_thin.rs and tests/stability_grazing.rs render (run from anywhere; the JSON files
are committed). Each scene is a place where a renderer's methods are known to fail; the tests
state what must hold there and compute it independently of the renderer.

mirror_corridor: two parallel mirrors of reflectance 1 at x = 0 and x = 1 (100 x 100 in y and
  z), the camera midway at (0.5, 0, 0) looking along +x, and a one-sided emitter panel
  (Le = 1, black behind) in the plane x = 0.5 at y in [0.5, 1], z in [-0.5, 0.5], facing +x.
  Unfolding the reflections, a camera ray of slopes (dy/dx, dz/dx) = (a, b) crosses images of the
  light plane at distances k = 1, 2, ..., seeing the emitter's front at odd k and its black back
  at even k, wherever (k a, k b) lies in the panel. A black square (half-size 0.0098) just in
  front of the far mirror at x = 0.99 covers the slopes max(|a|, |b|) < 0.02 around the axis:
  without it, rays ever closer to the axis reach the light after ever more bounces, and since
  Russian roulette divides the unit throughput by 0.95 per bounce, the variance of those pixels
  would be infinite (the light's area at crossing k falls as k^-3, the squared weight grows as
  0.95^-k). With it, every ray that reaches the light does so within 50 crossings; rays that miss
  it still bounce up to thousands of times before leaving the mirrors, so Russian roulette is what
  ends them.

thin_box: a closed diffuse box (albedo 0.8, the 12 triangles of a `boxes` entry) resting 1e-4
  above a diffuse floor (albedo 0.5) lit by a 6 x 6 emitter (Le = 1) at height 4; the camera is
  inside the box. No light can get in, so every sample must be exactly 0.
thin_box_gap: the same box built from six quads whose four side walls stop 1e-4 short of the
  bottom face: a slit 1e-4 high all round, through which the lit floor outside is visible.

thin_slab: a glass slab (ior 1.5, tint 1) 1e-4 thick, 20 x 20, between the camera (height 1,
  looking 40 degrees off straight down, vfov 80: incidence 0 to 82 degrees) and a uniform
  one-sided emitter (Le = 1) at z = -1 filling the view behind it; nothing else (reflected light
  leaves the scene). With incoherent internal reflections the slab transmits
  T = (1 - R) / (1 + R), R the unpolarised Fresnel reflectance at the incidence angle.

grazing: an enclosure x in [-2, 5.73], y in [-3, 3], z in [0.3 - 2, 0.3 + 2] split by a diffuse
  plane (albedo 0.8, 0.5, 0.2) at z = 0.3. The upper half's five faces emit Le = 1 inward (black
  emitters), the lower half's five faces are black (albedo 0). The plane sees only the emitting
  half, so every point of it has radiance albedo x Le exactly, from any direction. The camera at
  height 0.01 above the plane looks along +x with vfov 20: the plane fills the lower half of the
  image at incidence 80 to 89.9 degrees (the far wall at x = 5.73 is where the incidence reaches
  89.9: 0.01 / 5.73 = tan 0.1 degrees); above the wall-plane line the image is the emitting wall.
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def quad(p0, p1, p2, p3, material, part):
    """Two triangles (p0, p1, p2) and (p0, p2, p3); (p1 - p0) x (p2 - p0) is the front side."""
    return [
        {"v": [p0, p1, p2], "material": material, "part": part},
        {"v": [p0, p2, p3], "material": material, "part": part},
    ]


def x_rect(x, y0, y1, z0, z1, material, part, facing):
    """The rectangle x = const, y in [y0, y1], z in [z0, z1], front toward `facing` (+1 or -1)."""
    a, b, c, d = [x, y0, z0], [x, y1, z0], [x, y1, z1], [x, y0, z1]
    return quad(a, b, c, d, material, part) if facing > 0 else quad(a, d, c, b, material, part)


def y_rect(y, x0, x1, z0, z1, material, part, facing):
    a, b, c, d = [x0, y, z0], [x0, y, z1], [x1, y, z1], [x1, y, z0]
    return quad(a, b, c, d, material, part) if facing > 0 else quad(a, d, c, b, material, part)


def z_rect(z, x0, x1, y0, y1, material, part, facing):
    a, b, c, d = [x0, y0, z], [x1, y0, z], [x1, y1, z], [x0, y1, z]
    return quad(a, b, c, d, material, part) if facing > 0 else quad(a, d, c, b, material, part)


def mirror_corridor():
    L = 100.0
    tris = []
    tris += x_rect(0.0, -L, L, -L, L, "mirror", "mirror x = 0", +1)
    tris += x_rect(1.0, -L, L, -L, L, "mirror", "mirror x = 1", -1)
    tris += x_rect(0.5, 0.5, 1.0, -0.5, 0.5, "light", "emitter panel facing +x", +1)
    tris += x_rect(0.99, -0.0098, 0.0098, -0.0098, 0.0098, "black", "black square on the axis", -1)
    return {
        "name": "mirror_corridor",
        "seed": "two parallel unit mirrors with a one-sided emitter panel between them",
        "notes": [
            "mirrors x = 0 and x = 1; camera at (0.5, 0, 0) looking +x, image right = -y, up = +z",
            "emitter x = 0.5, y in [0.5, 1], z in [-0.5, 0.5], Le = 1, front +x, black behind",
            "black square x = 0.99, |y|, |z| <= 0.0098: slopes max(|dy/dx|, |dz/dx|) < 0.02 never"
            " reach the light, which bounds the number of bounces before the light at 50",
            "the expected image is an exact finite series over the unfolded light planes"
            " (tests/stability_mirror_corridor.rs)",
        ],
        "camera": {"eye": [0.5, 0.0, 0.0], "look_at": [1.5, 0.0, 0.0], "up": [0, 0, 1],
                   "vfov_deg": math.degrees(2.0 * math.atan(0.125)),
                   "note": "tan(vfov / 2) = 0.125: the image spans slopes [-0.125, 0.125]^2;"
                           " +y is image left"},
        "materials": {
            "mirror": {"type": "mirror", "reflectance": [1.0, 1.0, 1.0]},
            "light": {"type": "emitter", "radiance": [1.0, 1.0, 1.0]},
            "black": {"type": "diffuse", "albedo": [0.0, 0.0, 0.0]},
        },
        "triangles": tris,
    }


GAP = 1e-4


def lit_floor():
    return (z_rect(0.0, -10.0, 10.0, -10.0, 10.0, "floor", "floor", +1)
            + z_rect(4.0, -3.0, 3.0, -3.0, 3.0, "light", "emitter facing down", -1))


BOX_CAMERA = {"eye": [0.0, 0.0, 1.0], "look_at": [1.0, 1.0, GAP], "up": [0, 0, 1],
              "vfov_deg": 100.0,
              "note": "inside the box at its centre, looking at the bottom corner (1, 1, 1e-4)"}


def thin_box():
    return {
        "name": "thin_box",
        "seed": "a closed box 1e-4 above a lit floor, the camera inside",
        "notes": [
            "box [-1, 1] x [-1, 1] x [1e-4, 2], diffuse albedo 0.8 (12 triangles of a `boxes`"
            " entry, sharing edges); floor z = 0 albedo 0.5; emitter 6 x 6 at z = 4 facing down",
            "no light can enter the box: every sample is exactly 0",
        ],
        "camera": BOX_CAMERA,
        "materials": {
            "box": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]},
            "floor": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
            "light": {"type": "emitter", "radiance": [1.0, 1.0, 1.0]},
        },
        "triangles": lit_floor(),
        "boxes": [{"min": [-1.0, -1.0, GAP], "max": [1.0, 1.0, 2.0], "material": "box"}],
    }


def thin_box_gap():
    z0, z1, zw = GAP, 2.0, 2.0 * GAP
    faces = (z_rect(z0, -1.0, 1.0, -1.0, 1.0, "box", "bottom z = 1e-4", -1)
             + z_rect(z1, -1.0, 1.0, -1.0, 1.0, "box", "top", +1)
             + x_rect(-1.0, -1.0, 1.0, zw, z1, "box", "wall -x from z = 2e-4", -1)
             + x_rect(1.0, -1.0, 1.0, zw, z1, "box", "wall +x from z = 2e-4", +1)
             + y_rect(-1.0, -1.0, 1.0, zw, z1, "box", "wall -y from z = 2e-4", -1)
             + y_rect(1.0, -1.0, 1.0, zw, z1, "box", "wall +y from z = 2e-4", +1))
    return {
        "name": "thin_box_gap",
        "seed": "thin_box with a planted leak: the side walls stop 1e-4 above the bottom face",
        "notes": [
            "the same box as thin_box built from six quads, side walls from z = 2e-4: a slit"
            " 1e-4 high between the bottom face and the walls shows the lit floor outside",
        ],
        "camera": BOX_CAMERA,
        "materials": {
            "box": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]},
            "floor": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
            "light": {"type": "emitter", "radiance": [1.0, 1.0, 1.0]},
        },
        "triangles": lit_floor() + faces,
    }


def thin_slab():
    a = math.radians(40.0)
    return {
        "name": "thin_slab",
        "seed": "a glass slab 1e-4 thick in front of a uniform emitter",
        "notes": [
            "slab [-10, 10]^2 x [0, 1e-4], ior 1.5, tint 1; emitter z = -1, [-30, 30]^2, Le = 1,"
            " facing +z; nothing else",
            "expected pixel value: the pixel average of T = (1 - R) / (1 + R), R the unpolarised"
            " Fresnel reflectance at the ray's incidence angle",
        ],
        "camera": {"eye": [0.0, 0.0, 1.0], "look_at": [math.sin(a), 0.0, 1.0 - math.cos(a)],
                   "up": [0, 0, 1], "vfov_deg": 80.0,
                   "note": "40 degrees off straight down toward +x: incidence 0 to 82 degrees"},
        "materials": {
            "glass": {"type": "glass", "ior": 1.5, "tint": [1.0, 1.0, 1.0]},
            "light": {"type": "emitter", "radiance": [1.0, 1.0, 1.0]},
        },
        "triangles": z_rect(-1.0, -30.0, 30.0, -30.0, 30.0, "light", "emitter facing +z", +1),
        "boxes": [{"min": [-10.0, -10.0, 0.0], "max": [10.0, 10.0, GAP], "material": "glass"}],
    }


def grazing():
    zp, H = 0.3, 2.0
    x0, x1, Y = -2.0, 0.01 / math.tan(math.radians(0.1)), 3.0
    up, lo = (zp, zp + H), (zp - H, zp)
    tris = z_rect(zp, x0, x1, -Y, Y, "plane", "plane z = 0.3", +1)
    for (za, zb), m, tag in ((up, "sky", "upper"), (lo, "black", "lower")):
        tris += x_rect(x0, -Y, Y, za, zb, m, f"{tag} wall x = {x0}", +1)
        tris += x_rect(x1, -Y, Y, za, zb, m, f"{tag} far wall", -1)
        tris += y_rect(-Y, x0, x1, za, zb, m, f"{tag} wall y = -{Y}", +1)
        tris += y_rect(Y, x0, x1, za, zb, m, f"{tag} wall y = {Y}", -1)
    tris += z_rect(zp + H, x0, x1, -Y, Y, "sky", "ceiling", -1)
    tris += z_rect(zp - H, x0, x1, -Y, Y, "black", "floor", +1)
    return {
        "name": "grazing",
        "seed": "a diffuse plane splitting an enclosure whose upper half emits, seen at grazing"
                " angles",
        "notes": [
            f"plane z = {zp}, x in [{x0}, {x1}], y in [-{Y}, {Y}], albedo (0.8, 0.5, 0.2);"
            " upper half-enclosure: inward emitters Le = 1 (black); lower half: albedo 0",
            "every plane pixel is albedo x Le exactly, every pixel of the emitting wall Le;"
            " from below, the plane's underside is exactly 0",
        ],
        "camera": {"eye": [0.0, 0.0, zp + 0.01], "look_at": [1.0, 0.0, zp + 0.01],
                   "up": [0, 0, 1], "vfov_deg": 20.0,
                   "note": "0.01 above the plane looking along +x: the lower half of the image is"
                           " the plane at incidence 80 to 89.9 degrees"},
        "materials": {
            "plane": {"type": "diffuse", "albedo": [0.8, 0.5, 0.2]},
            "sky": {"type": "emitter", "radiance": [1.0, 1.0, 1.0]},
            "black": {"type": "diffuse", "albedo": [0.0, 0.0, 0.0]},
        },
        "triangles": tris,
    }


def write(name, data):
    with open(os.path.join(HERE, name + ".json"), "w") as f:
        json.dump(data, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    write("mirror_corridor", mirror_corridor())
    write("thin_box", thin_box())
    write("thin_box_gap", thin_box_gap())
    write("thin_slab", thin_slab())
    write("grazing", grazing())
