#!/usr/bin/env python3
"""The clearances and joint targets written in the comments of the geometry examples
(choreographies/mounted-arm.chor, sorting-case-study.chor and their rejected variants under
choreographies/rejected/geometry/), recomputed with urdf_fk.py. Run from the repository root:
    python3 robots/tools/example_clearances.py        (about a minute: the Moveo's meshes)
Estimates, not proofs: see urdf_fk.py. bridge.chor's numbers are boxes, computed in its
comment by hand.
"""
import itertools
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from urdf_fk import Urdf, pose, lerp, shapes_box_distance  # noqa: E402

MOVEO = Urdf("robots/moveo_urdf/urdf/moveo_urdf.urdf")
PANDA = Urdf("robots/example-robot-data/robots/panda_description/urdf/panda_collision.urdf")
# robots/moveo.mochi: the URDF placed so that Joint_1's axis is z and the arm reaches along +x.
MOVEO_URDF = pose(0.2069, 0.1265, 0, 0, 0, -1.022)
# robots/panda.mochi: panda_link0 on top of the 0.07 platform.
PANDA_URDF = pose(0, 0, 0.07)
ROVER_HALF_DIAG = math.hypot(0.07, 0.09)


def mq(j1, j2, j3, j4, j5):
    return dict(Joint_1=j1, Joint_2=j2, Joint_3=j3, Joint_4=j4, Joint_5=j5)


def pq(a):
    names = ["panda_joint%d" % i for i in range(1, 8)] + ["panda_finger_joint1"]
    return dict(zip(names, a))


def mounted_arm():
    print("== mounted-arm.chor (Base at the origin, deck 0.15, 1 cm spacer)")
    base = pose(0, 0, 0.16) * MOVEO_URDF
    plate = [s for s in MOVEO.shapes(mq(0, 0, 0, 0, 0), base) if s[0] == "base_link"][0][2]
    print("plate max radius: all %.4f, below z = 0.20: %.4f, lowest z %.4f" % (
        max(math.hypot(p[0], p[1]) for p in plate),
        max(math.hypot(p[0], p[1]) for p in plate if p[2] < 0.2), min(p[2] for p in plate)))
    rmax, zmin = 0.0, 9.0
    for k in range(25):
        q = mq(-1.2 + 2.4 * k / 24, 0.6, 0.6, 0, 0)
        for _, kind, data in MOVEO.shapes(q, base):
            if _ == "base_link":
                continue
            for p in data:
                rmax, zmin = max(rmax, math.hypot(p[0], p[1])), min(zmin, p[2])
    print("arm links during the swing: max radius %.4f, lowest z %.4f" % (rmax, zmin))
    corners = [(0.26 * a, 0.26 * b, 0.15) for a in (-1, 1) for b in (-1, 1)]
    for r in (0.70, 0.55):
        rin = r - 0.02 - ROVER_HALF_DIAG
        best = min((math.hypot(max(0, rin - math.hypot(p[0], p[1])), max(0, p[2] - 0.2)), tuple(round(c, 3) for c in p))
                   for p in plate)
        cart = rin - math.hypot(0.26, 0.26)
        init = shapes_box_distance([("plate", "pts", plate)], [r - 0.09, -0.07, 0], [r + 0.09, 0.07, 0.2])[0]
        print("orbit r = %.2f: Arm/Rover %.4f at %s, Base/Rover %.4f, initial Arm/Rover %.4f" % (r, best[0], best[1], cart, init))


def sorting():
    print("== sorting-case-study.chor")
    mw = pose(-0.1, 0.75, 0, 0, 0, -math.pi / 2) * MOVEO_URDF
    pw = pose(-0.2, -1.1, 0, 0, 0, math.pi / 2) * PANDA_URDF
    red = ([-0.185, 0.145, 0], [-0.015, 0.325, 0.16])
    green = ([-0.185, -0.49, 0], [-0.015, -0.31, 0.16])
    lane_y = ([-0.185, -0.49, 0], [-0.015, 0.09, 0.16])
    sensor = ([0.10, -0.10, 0], [0.20, 0.0, 0.20])
    m0, mp = mq(0, 0, 0, 0, 0), mq(0, -1.1, 0.9, 0, 0.6)
    sh = MOVEO.shapes(m0, mw)
    print("Moveo plate / carrier at the red stop %.4f" % shapes_box_distance([s for s in sh if s[0] == "base_link"], *red)[0])
    arm = lambda q: [s for s in MOVEO.shapes(q, mw) if s[0] != "base_link"]  # noqa: E731
    d = min(shapes_box_distance(arm(lerp(m0, mp, k / 10)), *red)[0] for k in range(11))
    print("Moveo M0 -> MP / carrier: %.4f (nominal)" % d)
    worst = min(shapes_box_distance(arm(mq(*[v + s * 0.063 for v, s in zip((0, -1.1, 0.9, 0, 0.6), sg)])), *red)[0]
                for sg in itertools.product((-1, 1), repeat=5))
    print("Moveo MP with +-3.6 degrees (2 x moveo_err at the start of the move back up): worst %.4f" % worst)
    H = (0, -0.785398, 0, -2.356195, 0, 1.570796, 0.785398, 0.04)
    PG = (-0.1419, 0.5143, 0, -1.3372, 0, 1.8516, 0.785398, 0.04)
    G = (-0.1419, 0.7121, 0, -1.5403, 0, 2.2525, 0.785398, 0.04)
    LOW = (-0.1419, 0.8345, 0, -1.5231, 0, 2.3576, 0.785398, 0.04)
    path = lambda a, b: [tuple(x + (y - x) * k / 8 for x, y in zip(a, b)) for k in range(9)]  # noqa: E731
    dist = lambda confs, box: min(shapes_box_distance(PANDA.shapes(pq(c), pw), *box)[0] for c in confs)  # noqa: E731
    for name, c in (("PG", PG), ("G", G), ("LOW", LOW)):
        t = PANDA.link_poses(pq(c), pw)["panda_hand_tcp"].apply([0, 0, 0])
        print("Panda %s tcp at (%.3f, %.3f, %.3f)" % (name, *t))
    print("Panda H -> PG / carrier anywhere on its way in: %.4f" % dist(path(H, PG), lane_y))
    print("Panda PG -> G / carrier at the green stop: %.4f" % dist(path(PG, G), green))
    worst = min(dist([tuple(v + s * 0.001 for v, s in zip(G[:7], sg)) + (0.04,)], green)
                for sg in itertools.product((-1, 1), repeat=7))
    print("Panda G with +-0.001 rad: worst %.4f" % worst)
    print("Panda / sensor over its motions: %.4f" % dist(path(H, PG) + path(PG, G), sensor))
    print("== rejected/geometry/sorting-panda-reaches-into-cart-path.chor (PG := LOW)")
    sh = PANDA.shapes(pq(LOW), pw)
    for k in range(81):
        yc = -0.005 * k
        d = shapes_box_distance(sh, [-0.185, yc - 0.09, 0], [-0.015, yc + 0.09, 0.16])
        if d[0] <= 0:
            print("the carrier first touches the lowered Panda at y = %.3f (t >= %.3f s): %s at %s" % (
                yc, -yc / 0.2, d[1], [round(v, 3) for v in d[2]]))
            break
    for i in range(201):
        t = i * 0.01
        c = tuple(a + (b - a) * min(t / 2.0, 1) for a, b in zip(H, LOW))
        ymin = max(-0.4, -0.2 * t)
        d = shapes_box_distance(PANDA.shapes(pq(c), pw), [-0.185, ymin - 0.09, 0], [-0.015, 0.09, 0.16])
        if d[0] <= 0:
            print("started together: first contact at t = %.2f s, %s at %s" % (t, d[1], [round(v, 3) for v in d[2]]))
            break


if __name__ == "__main__":
    mounted_arm()
    sorting()
