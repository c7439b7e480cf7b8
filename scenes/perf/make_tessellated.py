#!/usr/bin/env python3
"""Writes tncg15_room with every triangle split into n^2 (n = 3 and 10): the same surfaces, 9x and
100x the triangles, for measuring how the cost per camera path grows with the triangle count
(`hexray bench scenes/perf/*.json`). The images equal tncg15_room's: each sub-triangle lies in its
parent's plane with the parent's winding, so emitters keep their front side.

Run from anywhere; the JSON files are committed.
"""
import json
import os

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.join(HERE, "..", "tncg15_room.json")


def split(v, n):
    """The n^2 sub-triangles of triangle v on the barycentric grid of step 1/n, same winding."""
    p = lambda i, j: [v[0][k] + i / n * (v[1][k] - v[0][k]) + j / n * (v[2][k] - v[0][k])
                      for k in range(3)]
    out = []
    for i in range(n):
        for j in range(n - i):
            out.append([p(i, j), p(i + 1, j), p(i, j + 1)])
            if i + j < n - 1:
                out.append([p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)])
    return out


def main():
    with open(SOURCE) as f:
        base = json.load(f)
    for n in (3, 10):
        scene = json.loads(json.dumps(base))
        scene["name"] = f"tncg15_room_x{n * n}"
        scene["seed"] = f"tncg15_room.json with every triangle split into {n * n} (scenes/perf/make_tessellated.py)"
        scene["triangles"] = [
            {"v": sub, "material": t["material"], "part": t.get("part", "")}
            for t in base["triangles"]
            for sub in split(t["v"], n)
        ]
        path = os.path.join(HERE, f"tncg15_room_x{n * n}.json")
        with open(path, "w") as f:
            json.dump(scene, f)
            f.write("\n")
        print(f"{path}: {len(scene['triangles'])} triangles")


if __name__ == "__main__":
    main()
