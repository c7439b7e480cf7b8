#!/usr/bin/env python3
"""Writes the scenes of the robust-default tests (run from anywhere; the JSON files are
committed). Each is `scenes/tncg15_room.json` with a large quad 100 units below the room's floor
(z = -105), 10,000 units wide, which the camera never sees and the closed room keeps apart from
every path through the view:

  unseen_ground.json (tests/merge_radius.rs): the quad is a diffuse ground (albedo 0.5). The
      image is tncg15_room's exactly; a merge radius taken from the scene's bounds grows from
      0.335 to 212 with it.
  far_emitter.json (tests/dark_image.rs): the quad is a one-sided emitter (radiance 1) facing
      away from the room (-z). It holds nearly all of the scene's power, none of which reaches
      the camera, so the methods that pick emitters by power nearly always pick it.
"""
import copy
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))
Z, H = -105.0, 5000.0


def with_quad(room, name, seed, material, desc, facing_down):
    scene = copy.deepcopy(room)
    scene["name"] = name
    scene["seed"] = seed
    scene["materials"][material] = desc
    a, b, c, d = [-H, -H, Z], [H, -H, Z], [H, H, Z], [-H, H, Z]
    # (v1 - v0) x (v2 - v0) points down for (a, c, b) and (a, d, c), up for (a, b, c), (a, c, d).
    tris = [[a, c, b], [a, d, c]] if facing_down else [[a, b, c], [a, c, d]]
    scene["triangles"] += [{"v": v, "material": material, "part": name} for v in tris]
    return scene


def main():
    with open(os.path.join(HERE, "..", "tncg15_room.json")) as f:
        room = json.load(f)
    scenes = {
        "unseen_ground.json": with_quad(
            room,
            "unseen_ground",
            "tncg15_room with a ground quad 10,000 units wide, 100 units below its floor, "
            "which the camera never sees (make_stability_d.py)",
            "ground",
            {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
            facing_down=False,
        ),
        "far_emitter.json": with_quad(
            room,
            "far_emitter",
            "tncg15_room with an emitter 10,000 units wide, 100 units below its floor, facing "
            "away from it: nearly all of the scene's power, none of which reaches the camera "
            "(make_stability_d.py)",
            "far_light",
            {"type": "emitter", "radiance": [1, 1, 1], "one_sided": True},
            facing_down=True,
        ),
    }
    for name, scene in scenes.items():
        with open(os.path.join(HERE, name), "w") as f:
            json.dump(scene, f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
