"""The curves that `hexray curve` and benches/mitsuba_curve.py write, read back for the tables of
docs/figures/methods.sh and docs/figures/curves.sh (imported by both: `sys.path.insert(0, "benches")`)."""
import csv
import math
import os


def series(folder):
    """Every series of FOLDER/curve.csv (hexray's, by its backend column) and FOLDER/mitsuba.csv
    (Mitsuba's, named "mitsuba VARIANT"), each a list of (seconds, relmse, spp) in time order."""
    rows = []
    path = os.path.join(folder, "curve.csv")
    if os.path.exists(path):
        rows += [(r["backend"], float(r["seconds"]), float(r["relmse"]), int(r["spp"])) for r in csv.DictReader(open(path))]
    path = os.path.join(folder, "mitsuba.csv")
    if os.path.exists(path):
        rows += [("mitsuba " + r["variant"], float(r["seconds"]), float(r["relmse"]), int(r["spp"])) for r in csv.DictReader(open(path))]
    by = {}
    for b, s, e, n in rows:
        by.setdefault(b, []).append((s, e, n))
    return {b: sorted(v) for b, v in by.items()}


def at(points, t):
    """relMSE at time t, log-log between the waves around it (None outside the curve)."""
    for (s0, e0, _), (s1, e1, _) in zip(points, points[1:]):
        if s0 <= t <= s1 and e0 > 0 and e1 > 0:
            f = (math.log(t) - math.log(s0)) / (math.log(s1) - math.log(s0))
            return math.exp(math.log(e0) + f * (math.log(e1) - math.log(e0)))
    return None
