#!/usr/bin/env python3
"""make_anim_scene: writes scenes/anim-box/anim-box.gltf, a small animated Cornell-like room for the
dynamic-scene work of issue 19 (softgi reads glTF animations, skins and morph targets: pf_anim.h).

Usage:  python3 tools/make_anim_scene.py [output_root]      (default: the repository root)

The room (metres, right-handed, +Y up, glTF's conventions): x 0..4, y 0..3, z 0..4, open towards +z
where the camera stands; a white floor, ceiling and back wall, a red left wall (x = 0) and a green
right wall (x = 4), each an 8 x 8 grid of quads (so moved geometry's shadows land on many triangles).
In it, three animated objects, one per kind of motion:
  "box"     a 0.6 m cube moved by a TRS animation "move": translation LINEAR x 1.0 -> 3.0 -> 1.0
            over t = 0, 2, 4 s, and a rotation about +Y LINEAR 0 -> 90 -> 180 degrees at the same keys;
  "column"  a 0.3 x 2.0 x 0.3 m column of 16 segments, skinned to two joints ("base" at its foot,
            "bend" at y = 1.0) with weights blending linearly from 0.7 to 1.3 m: animation "sway" turns
            "bend" about +Z, 0 -> 30 -> -30 -> 0 degrees at t = 0, 1, 3, 4 s (a deforming object);
  "dome"    a 1.2 x 1.2 m floor patch of 16 x 16 quads with one morph target raising a dome of 0.35 m
            (POSITION and NORMAL deltas): animation "breathe" weights LINEAR 0 -> 1 -> 0 at t = 0, 2, 4 s.
A point light (KHR_lights_punctual, 12 W/sr, under the ceiling) and a perspective camera.
Every triangle is counter-clockwise seen from its front and carries explicit NORMALs. Standard library
only; only +, -, *, /, sqrt and the few trigonometric values of whole-degree keys (rounded to float32
far above libm differences) reach the buffers: same input, same bytes.
"""
import math
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_test_gltf as mt  # noqa: E402  (the Gltf writer)
from make_test_gltf import FLOAT, UBYTE, USHORT, UINT, f32, flat  # noqa: E402

WHITE, RED, GREEN = [0.73, 0.73, 0.73, 1.0], [0.63, 0.065, 0.05, 1.0], [0.14, 0.45, 0.091, 1.0]
YELLOW, BLUE, GREY = [0.75, 0.62, 0.3, 1.0], [0.25, 0.35, 0.7, 1.0], [0.6, 0.6, 0.6, 1.0]


def quat_axis(axis, degrees):
    h = math.radians(degrees) / 2.0
    s = math.sin(h)
    return [axis[0] * s, axis[1] * s, axis[2] * s, math.cos(h)]


class Mesh:
    """Positions, normals and triangle indices of one primitive."""

    def __init__(self):
        self.p, self.n, self.i = [], [], []

    def quad(self, a, b, c, d, n):
        """Quad a b c d, counter-clockwise about n."""
        k = len(self.p)
        self.p += [a, b, c, d]
        self.n += [n] * 4
        self.i += [k, k + 1, k + 2, k, k + 2, k + 3]

    def grid(self, origin, du, dv, n, cells):
        """cells x cells quads spanning origin + [0,1] du + [0,1] dv (du x dv along n)."""
        for y in range(cells):
            for x in range(cells):
                def at(u, v):
                    return tuple(origin[k] + du[k] * u / cells + dv[k] * v / cells for k in range(3))
                self.quad(at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1), n)


def add_mesh(g, m, material, extra_attrs=None, targets=None, weights=None):
    pos = g.vec3(m.p)
    nrm = g.vec3(m.n, bounds=False)
    ctype = USHORT if len(m.p) < 65536 else UINT
    prim = g.prim(pos, nrm, idx=g.indices(m.i, ctype), material=material)
    if extra_attrs:
        prim["attributes"].update(extra_attrs)
    if targets:
        prim["targets"] = targets
    mesh = {"primitives": [prim]}
    if weights:
        mesh["weights"] = weights
    return g.add("meshes", mesh)


def room(g, mats):
    cells = 8
    for name, origin, du, dv, n, mat in (
        ("floor", (0, 0, 4), (4, 0, 0), (0, 0, -4), (0, 1, 0), mats["white"]),
        ("ceiling", (0, 3, 0), (4, 0, 0), (0, 0, 4), (0, -1, 0), mats["white"]),
        ("back", (0, 0, 0), (4, 0, 0), (0, 3, 0), (0, 0, 1), mats["white"]),
        ("left", (0, 0, 4), (0, 0, -4), (0, 3, 0), (1, 0, 0), mats["red"]),
        ("right", (4, 0, 0), (0, 0, 4), (0, 3, 0), (-1, 0, 0), mats["green"]),
    ):
        m = Mesh()
        m.grid(origin, du, dv, n, cells)
        g.node(name=name, mesh=add_mesh(g, m, mat))


def cube(half):
    m = Mesh()
    h = half
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = sign
            u = [0.0, 0.0, 0.0]
            v = [0.0, 0.0, 0.0]
            u[(axis + 1) % 3] = 1.0
            v[(axis + 2) % 3] = 1.0
            if sign < 0:
                u, v = v, u

            def corner(a, b):
                return tuple(n[k] * h + (u[k] * a + v[k] * b) * h for k in range(3))
            m.quad(corner(-1, -1), corner(1, -1), corner(1, 1), corner(-1, 1), tuple(n))
    return m


def column(g, mats):
    """The skinned column: 16 segments, four sides each with their own vertices (sharp edges), caps."""
    w, height, segs = 0.15, 2.0, 16
    m = Mesh()
    sides = [((1, 0, 0), (0, 0, -1)), ((0, 0, 1), (1, 0, 0)), ((-1, 0, 0), (0, 0, 1)), ((0, 0, -1), (-1, 0, 0))]
    for n, t in sides:  # t: the side's horizontal direction, n x t = +Y (counter-clockwise about n)
        for s in range(segs):
            y0, y1 = height * s / segs, height * (s + 1) / segs

            def p(a, y):
                return (n[0] * w + t[0] * w * a, y, n[2] * w + t[2] * w * a)
            m.quad(p(-1, y0), p(1, y0), p(1, y1), p(-1, y1), n)
    m.quad((-w, height, w), (w, height, w), (w, height, -w), (-w, height, -w), (0, 1, 0))
    m.quad((-w, 0, -w), (w, 0, -w), (w, 0, w), (-w, 0, w), (0, -1, 0))
    joints, weights = [], []
    for (_, y, _) in m.p:
        b = min(1.0, max(0.0, (y - 0.7) / 0.6))  # 0 below 0.7 m, 1 above 1.3 m
        joints.append((0, 1, 0, 0))
        weights.append((1.0 - b, b, 0.0, 0.0))
    jv = g.view(b"".join(struct.pack("<4B", *j) for j in joints))
    ja = g.accessor(jv, UBYTE, len(joints), "VEC4")
    wa = g.accessor(g.view(f32(flat(weights))), FLOAT, len(weights), "VEC4")
    return add_mesh(g, m, mats["blue"], {"JOINTS_0": ja, "WEIGHTS_0": wa})


def dome(g, mats):
    """A floor patch and its morph target: the height h = H (1 - r^2 / R^2) inside R."""
    size, cells, H, R = 1.2, 16, 0.35, 0.6
    m = Mesh()
    m.grid((-size / 2, 0, size / 2), (size, 0, 0), (0, 0, -size), (0, 1, 0), cells)
    dp, dn = [], []
    for (x, _, z) in m.p:
        r2 = x * x + z * z
        if r2 < R * R:
            h = H * (1.0 - r2 / (R * R))
            gx, gz = -2.0 * H * x / (R * R), -2.0 * H * z / (R * R)  # dh/dx, dh/dz
            ln = math.sqrt(gx * gx + 1.0 + gz * gz)
            dp.append((0.0, h, 0.0))
            dn.append((-gx / ln, 1.0 / ln - 1.0, -gz / ln))
        else:
            dp.append((0.0, 0.0, 0.0))
            dn.append((0.0, 0.0, 0.0))
    targets = [{"POSITION": g.vec3(dp), "NORMAL": g.vec3(dn, bounds=False)}]
    return add_mesh(g, m, mats["grey"], targets=targets, weights=[0.0])


def scalars(g, values):
    return g.accessor(g.view(f32(values)), FLOAT, len(values), "SCALAR", minv=[min(values)], maxv=[max(values)])


def keys(g, values, atype):
    return g.accessor(g.view(f32(flat(values))), FLOAT, len(values), atype)


def animation(g, name, channels):
    """channels: (node, path, times, values, atype)"""
    anim = {"name": name, "channels": [], "samplers": []}
    for k, (node, path, times, values, atype) in enumerate(channels):
        out = scalars(g, values) if atype == "SCALAR" else keys(g, values, atype)
        anim["samplers"].append({"input": scalars(g, times), "output": out})
        anim["channels"].append({"sampler": k, "target": {"node": node, "path": path}})
    g.add("animations", anim)


def build():
    g = mt.Gltf()
    g.doc["asset"]["generator"] = "softgi tools/make_anim_scene.py"
    g.doc["extensionsUsed"] = ["KHR_lights_punctual"]
    g.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "bulb", "type": "point", "color": [1.0, 1.0, 1.0], "intensity": 12.0}]}}
    mats = {}
    for name, c in (("white", WHITE), ("red", RED), ("green", GREEN), ("yellow", YELLOW), ("blue", BLUE),
                    ("grey", GREY)):
        mats[name] = g.add("materials", {"name": name, "pbrMetallicRoughness": {"baseColorFactor": c}})
    room(g, mats)                                                              # nodes 0..4
    box = g.node(name="box", translation=[1.0, 0.3, 2.2], mesh=add_mesh(g, cube(0.3), mats["yellow"]))  # 5
    base = g.node(name="base", translation=[2.9, 0.0, 1.0], children=[7])                                # 6
    bend = g.node(name="bend", translation=[0.0, 1.0, 0.0])                                             # 7
    g.add("skins", {"joints": [base, bend], "skeleton": base, "inverseBindMatrices": keys(
        g, [[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1],      # the mesh is in "base"'s space
            [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1.0, 0, 1]], "MAT4")})  # "bend" 1 m above it
    col = g.node(name="column", mesh=column(g, mats), skin=0)                                            # 8
    dm = g.node(name="dome", translation=[1.3, 0.0, 0.9], mesh=dome(g, mats))                            # 9
    light = g.node(name="bulb", translation=[2.0, 2.8, 2.0], extensions={"KHR_lights_punctual": {"light": 0}})
    g.add("cameras", {"name": "view", "type": "perspective",
                      "perspective": {"yfov": math.radians(50.0), "znear": 0.05, "zfar": 100.0}})
    cam = g.node(name="view", translation=[2.0, 1.5, 7.2], rotation=quat_axis((1, 0, 0), -4.0), camera=0)
    g.scene([0, 1, 2, 3, 4, box, base, col, dm, light, cam])
    animation(g, "move", [
        (box, "translation", [0.0, 2.0, 4.0], [(1.0, 0.3, 2.2), (3.0, 0.3, 2.2), (1.0, 0.3, 2.2)], "VEC3"),
        (box, "rotation", [0.0, 2.0, 4.0],
         [quat_axis((0, 1, 0), 0.0), quat_axis((0, 1, 0), 90.0), quat_axis((0, 1, 0), 180.0)], "VEC4"),
    ])
    animation(g, "sway", [(bend, "rotation", [0.0, 1.0, 3.0, 4.0],
                           [quat_axis((0, 0, 1), a) for a in (0.0, 30.0, -30.0, 0.0)], "VEC4")])
    animation(g, "breathe", [(dm, "weights", [0.0, 2.0, 4.0], [0.0, 1.0, 0.0], "SCALAR")])
    return g


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..")
    w = mt.Writer(os.path.normpath(os.path.join(root, "scenes", "anim-box")))
    w.gltf("anim-box.gltf", build())
    print("wrote %s" % os.path.join(w.outdir, "anim-box.gltf"))


if __name__ == "__main__":
    main()
