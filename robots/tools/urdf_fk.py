#!/usr/bin/env python3
"""Forward kinematics and point clouds of URDF collision geometry, for checking by hand the
clearances written in choreographies/*.chor comments. Pure Python (no numpy), independent of
mochi's geometry engine (checker/geometry/), so the two can be compared.

Not a verifier: distances are computed between finite point sets (mesh vertices, sampled
rims of cylinders, sphere centres minus radii), so a printed clearance is an estimate, never
below the true value by more than the sampling step of cylinder rims (10 degrees, about
0.4 % of the radius) and exact for mesh vertices and spheres against boxes.

Usage as a library (robots/tools/example_clearances.py computes the numbers written in the
geometry examples' comments):
    robot = Urdf("robots/moveo_urdf/urdf/moveo_urdf.urdf")
    shapes = robot.shapes({"Joint_1": 0.3, ...}, pose(x, y, z, roll, pitch, yaw))
    shapes_box_distance(shapes, lo, hi)   # (distance, link, nearest point)
"""
import math
import os
import struct
import xml.etree.ElementTree as ET


def rpy_matrix(r, p, y):
    # URDF: R = Rz(yaw) Ry(pitch) Rx(roll), as mochi's pose(...).
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]


def axis_angle(axis, a):
    n = math.sqrt(sum(c * c for c in axis))
    x, y, z = (c / n for c in axis)
    c, s, C = math.cos(a), math.sin(a), 1 - math.cos(a)
    return [
        [c + x * x * C, x * y * C - z * s, x * z * C + y * s],
        [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
        [z * x * C - y * s, z * y * C + x * s, c + z * z * C],
    ]


def mm(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def mv(a, v):
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


class T:
    """A rigid transform (R, t)."""

    def __init__(self, R=None, t=None):
        self.R = R or [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
        self.t = t or [0.0, 0.0, 0.0]

    def __mul__(self, o):
        return T(mm(self.R, o.R), [a + b for a, b in zip(mv(self.R, o.t), self.t)])

    def apply(self, p):
        return [a + b for a, b in zip(mv(self.R, p), self.t)]


def pose(x=0, y=0, z=0, r=0, p=0, yaw=0):
    return T(rpy_matrix(r, p, yaw), [x, y, z])


def origin(el):
    o = el.find("origin") if el is not None else None
    if o is None:
        return T()
    xyz = [float(v) for v in o.get("xyz", "0 0 0").split()]
    rpy = [float(v) for v in o.get("rpy", "0 0 0").split()]
    return pose(*xyz, *rpy)


def read_stl(path):
    with open(path, "rb") as f:
        data = f.read()
    n = struct.unpack_from("<I", data, 80)[0]
    if 84 + 50 * n == len(data):
        pts = set()
        for i in range(n):
            off = 84 + 50 * i + 12
            for k in range(3):
                pts.add(struct.unpack_from("<3f", data, off + 12 * k))
        return [list(p) for p in pts]
    pts = set()
    for line in data.decode("ascii", "replace").splitlines():
        w = line.split()
        if w and w[0] == "vertex":
            pts.add(tuple(float(v) for v in w[1:4]))
    return [list(p) for p in pts]


class Urdf:
    def __init__(self, path):
        self.path = path
        self.root = ET.parse(path).getroot()
        self.links = {l.get("name"): l for l in self.root.findall("link")}
        self.joints = self.root.findall("joint")
        children = {j.find("child").get("link") for j in self.joints}
        self.base = next(n for n in self.links if n not in children)
        self._mesh = {}

    def resolve(self, fn):
        if fn.startswith("package://"):
            # the package root is the folder containing the package folder
            pkg_root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(self.path))))
            rest = fn[len("package://"):]
            cand = os.path.join(pkg_root, rest)
            if os.path.exists(cand):
                return cand
            # example-robot-data layout: package://example-robot-data/robots/...
            up = pkg_root
            for _ in range(4):
                up = os.path.dirname(up)
                if os.path.exists(os.path.join(up, rest)):
                    return os.path.join(up, rest)
            return cand
        return os.path.join(os.path.dirname(self.path), fn)

    def movable(self):
        return [j.get("name") for j in self.joints if j.get("type") != "fixed" and j.find("mimic") is None]

    def link_poses(self, q, base=None):
        q = dict(q)
        out = {self.base: base or T()}
        pending = list(self.joints)
        while pending:
            rest = []
            for j in pending:
                parent = j.find("parent").get("link")
                if parent not in out:
                    rest.append(j)
                    continue
                m = j.find("mimic")
                name = j.get("name")
                if m is not None:
                    v = float(m.get("multiplier", "1")) * q.get(m.get("joint"), 0.0) + float(m.get("offset", "0"))
                else:
                    v = q.get(name, 0.0)
                tf = out[parent] * origin(j)
                ax = [float(c) for c in (j.find("axis").get("xyz") if j.find("axis") is not None else "1 0 0").split()]
                if j.get("type") in ("revolute", "continuous"):
                    tf = tf * T(axis_angle(ax, v))
                elif j.get("type") == "prismatic":
                    n = math.sqrt(sum(c * c for c in ax))
                    tf = tf * T(None, [c / n * v for c in ax])
                out[j.find("child").get("link")] = tf
            if len(rest) == len(pending):
                raise ValueError("disconnected joints")
            pending = rest
        return out

    def shapes(self, q, base=None):
        """(kind, data) per collision element in the world: ("pts", points) or ("sphere", (c, r))."""
        res = []
        for name, tf in self.link_poses(q, base).items():
            for c in self.links[name].findall("collision"):
                g = c.find("geometry")
                ct = tf * origin(c)
                if g.find("mesh") is not None:
                    fn = self.resolve(g.find("mesh").get("filename"))
                    if fn not in self._mesh:
                        self._mesh[fn] = read_stl(fn)
                    s = [float(v) for v in g.find("mesh").get("scale", "1 1 1").split()]
                    res.append((name, "pts", [ct.apply([p[0] * s[0], p[1] * s[1], p[2] * s[2]]) for p in self._mesh[fn]]))
                elif g.find("sphere") is not None:
                    res.append((name, "sphere", (ct.apply([0, 0, 0]), float(g.find("sphere").get("radius")))))
                elif g.find("cylinder") is not None:
                    r = float(g.find("cylinder").get("radius"))
                    h = float(g.find("cylinder").get("length"))
                    pts = []
                    for k in range(36):
                        a = 2 * math.pi * k / 36
                        for z in (-h / 2, h / 2):
                            pts.append(ct.apply([r * math.cos(a), r * math.sin(a), z]))
                    res.append((name, "pts", pts))
                elif g.find("box") is not None:
                    sx, sy, sz = (float(v) for v in g.find("box").get("size").split())
                    pts = [ct.apply([a * sx / 2, b * sy / 2, c2 * sz / 2]) for a in (-1, 1) for b in (-1, 1) for c2 in (-1, 1)]
                    res.append((name, "pts", pts))
        return res


def box_distance(p, lo, hi):
    """Distance from point p to the axis-aligned box [lo, hi] (0 inside)."""
    return math.sqrt(sum(max(l - c, 0, c - h) ** 2 for c, l, h in zip(p, lo, hi)))


def shapes_box_distance(shapes, lo, hi):
    best = (float("inf"), None, None)
    for link, kind, data in shapes:
        if kind == "sphere":
            c, r = data
            d = box_distance(c, lo, hi) - r
            if d < best[0]:
                best = (d, link, c)
        else:
            for p in data:
                d = box_distance(p, lo, hi)
                if d < best[0]:
                    best = (d, link, p)
    return best


def extent(shapes):
    """Bounding box of the shapes and their largest horizontal distance from the z axis."""
    lo, hi, rmax = [float("inf")] * 3, [-float("inf")] * 3, 0.0
    for _, kind, data in shapes:
        items = [data] if kind == "sphere" else [(p, 0.0) for p in data]
        for p, r in items:
            for i in range(3):
                lo[i] = min(lo[i], p[i] - r)
                hi[i] = max(hi[i], p[i] + r)
            rmax = max(rmax, math.hypot(p[0], p[1]) + r)
    return lo, hi, rmax


def lerp(a, b, s):
    return {k: a[k] + (b[k] - a[k]) * s for k in a}
