#!/usr/bin/env python3
"""make_anim_gltf: writes the small animated glTF files tests/test_anim.c checks, into
tests/data/gltf/anim/ (standard library only, deterministic bytes; the buffers are embedded
base64 data uris). It reuses the Gltf writer of tools/make_test_gltf.py.

Good files (anim_*.gltf) exercise one part of glTF 2.0 animation each (Sec. 3.11 animations,
3.7.3 skins, 3.7.2.2 morph targets, Appendix C interpolation), with keys chosen so the poses
are exact or nearly so (90-degree rotations, powers of two); the expected poses are derived in
the comments below and in test_anim.c next to each case. Bad files (bad_*.gltf) break exactly one
rule the loader must catch, each with a clean error.

Usage: python3 tools/make_anim_gltf.py [OUTPUT_DIR]
"""
import copy
import json
import math
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import make_test_gltf as mt  # noqa: E402  (the Gltf writer, the constants)

from make_test_gltf import FLOAT, UBYTE, USHORT, S, TRI, UP, f32, flat  # noqa: E402

NAN = float("nan")


def scalars(g, values, ctype=FLOAT, normalized=False):
    """A SCALAR accessor (animation times, morph weights)."""
    fmt = {FLOAT: "f", UBYTE: "B", USHORT: "H"}[ctype]
    v = g.view(struct.pack("<%d%s" % (len(values), fmt), *values))
    mn = mx = None
    if ctype == FLOAT and all(x == x for x in values):
        mn, mx = [min(values)], [max(values)]
    return g.accessor(v, ctype, len(values), "SCALAR", normalized=normalized, minv=mn, maxv=mx)


def vecs(g, values, atype, ctype=FLOAT, normalized=False):
    """A VEC3/VEC4 accessor of the given components (keys, joints, weights)."""
    n = {"VEC3": 3, "VEC4": 4}[atype]
    fmt = {FLOAT: "f", UBYTE: "B", USHORT: "H"}[ctype]
    data = flat(values)
    raw = b"".join(struct.pack("<%d%s" % (n, fmt), *data[i:i + n]) for i in range(0, len(data), n))
    # JOINTS/WEIGHTS of u8 are 4 bytes, u16 8 bytes: already 4-byte aligned elements
    v = g.view(raw)
    return g.accessor(v, ctype, len(values), atype, normalized=normalized)


def sampler(g, times, values, atype, interp=None):
    s = {"input": scalars(g, times), "output": vecs(g, values, atype) if atype != "SCALAR" else scalars(g, values)}
    if interp:
        s["interpolation"] = interp
    return s


def animation(g, name, channels, samplers):
    a = {"channels": [{"sampler": s, "target": {"node": n, "path": p}} for (s, n, p) in channels],
         "samplers": samplers}
    if name:
        a["name"] = name
    return g.add("animations", a)


def tri_prim(g, z=0.0, normals=True):
    pos = g.vec3([(x, y, z) for (x, y, _) in TRI])
    nrm = g.vec3([UP] * 3, bounds=False) if normals else None
    return g.prim(pos, nrm)


# ------------------------------------------------------------------ good files


def linear_file():
    """anim_linear.gltf: node 0 "box" holds TRI (normals +Z). Four animations on it:
      0 "slide": translation LINEAR, t = 0, 1, 2: (0,0,0) (2,0,0) (2,4,0)
      1 "spin":  rotation LINEAR, t = 1, 3: identity, then (0,0,-S,-S) = 90 degrees about +Z
                 written negated, so only the shortest path gives 45 degrees at t = 2
      2 "grow":  scale STEP, t = 0, 1: (1,1,1), (2,2,2)
      3 "slide": a second animation named "slide" (find by name takes the first), translation of
                 node 1 (static otherwise)
    Node 1 "still" holds TRI at z = 5 and is animated only by animation 3."""
    g = mt.Gltf()
    m0 = g.mesh([tri_prim(g)])
    m1 = g.mesh([tri_prim(g, z=5.0)])
    g.node(name="box", mesh=m0)
    g.node(name="still", mesh=m1)
    g.scene([0, 1])
    animation(g, "slide", [(0, 0, "translation")],
              [sampler(g, [0.0, 1.0, 2.0], [(0.0, 0.0, 0.0), (2.0, 0.0, 0.0), (2.0, 4.0, 0.0)], "VEC3")])
    animation(g, "spin", [(0, 0, "rotation")],
              [sampler(g, [1.0, 3.0], [(0.0, 0.0, 0.0, 1.0), (0.0, 0.0, -S, -S)], "VEC4")])
    animation(g, "grow", [(0, 0, "scale")],
              [sampler(g, [0.0, 1.0], [(1.0, 1.0, 1.0), (2.0, 2.0, 2.0)], "VEC3", "STEP")])
    animation(g, "slide", [(0, 1, "translation")],
              [sampler(g, [0.0, 1.0], [(0.0, 0.0, 0.0), (0.0, 8.0, 0.0)], "VEC3")])
    return g


def cubic_file():
    """anim_cubic.gltf: node 0 holds TRI. Animation 0 "curve":
      translation CUBICSPLINE, t = 0, 2, keys (in, value, out):
        key 0: (0,0,0) (0,0,0) (2,0,0);  key 1: (1,0,0) (4,0,0) (0,0,0)
        p(s) = h00 v0 + td h10 b0 + h01 v1 + td h11 a1, td = 2:
        t = 1 (s = 1/2): 0 + 2 (1/8) 2 + (1/2) 4 + 2 (-1/8) 1 = 2.25
        t = 0.5 (s = 1/4): 2 (9/64) 2 + (5/32) 4 + 2 (-3/64) 1 = 1.09375
      rotation CUBICSPLINE, t = 0, 2, zero tangents, identity then 90 degrees about +Z:
        at t = 1 the normalised mean of the two: 45 degrees about +Z."""
    g = mt.Gltf()
    g.node(name="curve", mesh=g.mesh([tri_prim(g)]))
    z3, z4 = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0)
    tr = [z3, z3, (2.0, 0.0, 0.0), (1.0, 0.0, 0.0), (4.0, 0.0, 0.0), z3]
    rot = [z4, (0.0, 0.0, 0.0, 1.0), z4, z4, (0.0, 0.0, S, S), z4]
    animation(g, "curve", [(0, 0, "translation"), (1, 0, "rotation")],
              [sampler(g, [0.0, 2.0], tr, "VEC3", "CUBICSPLINE"), sampler(g, [0.0, 2.0], rot, "VEC4", "CUBICSPLINE")])
    return g


def skin_file():
    """anim_skin.gltf: a two-joint bend. A strip of 6 vertices (x, y) for y = 0, 1, 2 and x = 0, 1,
    4 triangles, normals +Z. Joints: node 0 "root" (at the origin) and its child node 1 "elbow" at
    T(0,1,0); inverse bind matrices identity and T(0,-1,0). Influences over two sets:
      y = 0: JOINTS_0 (u8) 0, WEIGHTS_0 (normalized u8) 255 = 1.0
      y = 1: JOINTS_1 (u16) 0 and 1, WEIGHTS_1 (float) 0.5 and 0.5
      y = 2: JOINTS_1 1, WEIGHTS_1 1.0
    The skinned mesh node 2 has T(100,0,0), which must be ignored (glTF 2.0 Sec. 3.7.3.1).
    Animation 0 "bend": the elbow's rotation LINEAR, t = 0, 1: identity, 90 degrees about +Z.
    At t = 1: y = 2 vertices (x,2,0) -> T(0,1,0) R90 (x,1,0) = (-1, 1 + x, 0);
              y = 1 vertices (x,1,0) -> 0.5 (x,1,0) + 0.5 (0, 1 + x, 0) = (x/2, 1 + x/2, 0);
              y = 0 vertices stay. The static pose is the strip itself."""
    g = mt.Gltf()
    verts = [(x, y, 0.0) for y in (0.0, 1.0, 2.0) for x in (0.0, 1.0)]
    pos = g.vec3(verts)
    nrm = g.vec3([UP] * 6, bounds=False)
    idx = g.indices([0, 1, 3, 0, 3, 2, 2, 3, 5, 2, 5, 4], USHORT)
    j0 = vecs(g, [(0, 0, 0, 0)] * 6, "VEC4", UBYTE)
    w0 = vecs(g, [(255, 0, 0, 0)] * 2 + [(0, 0, 0, 0)] * 4, "VEC4", UBYTE, normalized=True)
    j1 = vecs(g, [(0, 0, 0, 0)] * 2 + [(0, 1, 0, 0)] * 2 + [(1, 0, 0, 0)] * 2, "VEC4", USHORT)
    w1 = vecs(g, [(0.0, 0.0, 0.0, 0.0)] * 2 + [(0.5, 0.5, 0.0, 0.0)] * 2 + [(1.0, 0.0, 0.0, 0.0)] * 2, "VEC4")
    p = g.prim(pos, nrm, idx=idx)
    p["attributes"].update({"JOINTS_0": j0, "WEIGHTS_0": w0, "JOINTS_1": j1, "WEIGHTS_1": w1})
    mesh = g.mesh([p])
    ibm = g.accessor(g.view(f32([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1] +
                                [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -1, 0, 1])), FLOAT, 2, "MAT4")
    g.node(name="root", children=[1])
    g.node(name="elbow", translation=[0.0, 1.0, 0.0])
    g.node(name="skinned", translation=[100.0, 0.0, 0.0], mesh=mesh, skin=0)
    g.add("skins", {"joints": [0, 1], "inverseBindMatrices": ibm, "skeleton": 0})
    g.scene([0, 2])
    animation(g, "bend", [(0, 1, "rotation")],
              [sampler(g, [0.0, 1.0], [(0.0, 0.0, 0.0, 1.0), (0.0, 0.0, S, S)], "VEC4")])
    return g


def morph_file():
    """anim_morph.gltf: mesh 0 = TRI with normals +Z and two morph targets:
      target 0: POSITION (0,0,1) at every vertex, no NORMAL
      target 1: POSITION (1,0,0) and NORMAL (1,0,0) at vertex 1 only
    mesh weights [0.5, 0]. Node 0 "morphing" (mesh weights; static: z = 0.5 everywhere);
    node 1 "fixed" at T(0,0,5) with node weights [0, 1] (static: vertex 1 at (2,0,5), normal
    (1,0,1)/sqrt2), never animated. Animations:
      0 "blend": node 0's weights LINEAR, t = 0, 1: [0,0] -> [1,1];
         t = 0.5: w = (0.5, 0.5): (0,0,0.5) (1.5,0,0.5) (0,1,0.5); normal 1 = (1,0,2)/sqrt5
      1 "snap": node 0's weights STEP, t = 0, 1: [0,0] -> [1,0]: z = 0 before t = 1, 1 from it."""
    g = mt.Gltf()
    pos = g.vec3(TRI)
    nrm = g.vec3([UP] * 3, bounds=False)
    t0 = g.vec3([(0.0, 0.0, 1.0)] * 3, bounds=False)
    t1p = g.vec3([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 0.0)], bounds=False)
    t1n = g.vec3([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 0.0)], bounds=False)
    p = g.prim(pos, nrm)
    p["targets"] = [{"POSITION": t0}, {"POSITION": t1p, "NORMAL": t1n}]
    mesh = g.add("meshes", {"primitives": [p], "weights": [0.5, 0.0]})
    g.node(name="morphing", mesh=mesh)
    g.node(name="fixed", mesh=mesh, translation=[0.0, 0.0, 5.0], weights=[0.0, 1.0])
    g.scene([0, 1])
    animation(g, "blend", [(0, 0, "weights")], [sampler(g, [0.0, 1.0], [0.0, 0.0, 1.0, 1.0], "SCALAR")])
    animation(g, "snap", [(0, 0, "weights")], [sampler(g, [0.0, 1.0], [0.0, 0.0, 1.0, 0.0], "SCALAR", "STEP")])
    return g


def hierarchy_file():
    """anim_hierarchy.gltf: node 0 "arm" (rotation animated), its child node 1 "hand" at T(1,0,0)
    (translation animated) holds TRI with normals and a flat-shaded copy (no NORMAL) at z = 1;
    node 2 "base" is a static root holding TRI at z = -1 (never moves). Animation 0 "wave":
      arm rotation LINEAR t = 0, 1: identity -> 90 degrees about +Z
      hand translation LINEAR t = 0, 1: (1,0,0) -> (2,0,0)
    At t = 1: hand world = R90 T(2,0,0); TRI (0,0,0) (1,0,0) (0,1,0) -> (0,2,0) (0,3,0) (-1,2,0);
    normals stay +Z (a rotation about Z). At t = 0.5: arm 45 degrees, hand at (1.5,0,0): TRI vertex
    0 at 1.5 (c, s, 0), c = s = sqrt(1/2)."""
    g = mt.Gltf()
    smooth = tri_prim(g)
    flat_p = tri_prim(g, z=1.0, normals=False)
    m0 = g.mesh([smooth, flat_p])
    m1 = g.mesh([tri_prim(g, z=-1.0)])
    g.node(name="arm", children=[1])
    g.node(name="hand", translation=[1.0, 0.0, 0.0], mesh=m0)
    g.node(name="base", mesh=m1)
    g.scene([0, 2])
    animation(g, "wave", [(0, 0, "rotation"), (1, 1, "translation")],
              [sampler(g, [0.0, 1.0], [(0.0, 0.0, 0.0, 1.0), (0.0, 0.0, S, S)], "VEC4"),
               sampler(g, [0.0, 1.0], [(1.0, 0.0, 0.0), (2.0, 0.0, 0.0)], "VEC3")])
    return g


def far_file():
    """anim_far.gltf: TRI on node 0, translation LINEAR t = 0, 1: (0,0,0) -> (1e30,0,0): the
    static pose loads, t = 1 lands beyond PF_SCENE_MAX_COORD and must be refused (the scene
    then stays in its previous pose)."""
    g = mt.Gltf()
    g.node(name="runaway", mesh=g.mesh([tri_prim(g)]))
    animation(g, "away", [(0, 0, "translation")],
              [sampler(g, [0.0, 1.0], [(0.0, 0.0, 0.0), (1.0e30, 0.0, 0.0)], "VEC3")])
    return g


# ------------------------------------------------------------------ bad files


def bad_files(w):
    """Each bad_*.gltf breaks one rule; the comment says which and the expected pf_result."""

    def lin(mut):
        g = linear_file()
        mut(g)
        return g

    def set_bytes(g, accessor, values):
        """Overwrites accessor `accessor`'s float data in the buffer (NaN is not JSON)."""
        a = g.doc["accessors"][accessor]
        v = g.doc["bufferViews"][a["bufferView"]]
        off = v["byteOffset"] + a.get("byteOffset", 0)
        g.bin[off:off + 4 * len(values)] = f32(values)
        a.pop("min", None)
        a.pop("max", None)

    def slide(g):  # animation 0's sampler 0
        return g.doc["animations"][0]["samplers"][0]

    cases = {
        # PF_ERR_INDEX_RANGE
        "bad_anim_node_index.gltf": lambda g: g.doc["animations"][0]["channels"][0]["target"].update(node=9),
        "bad_anim_sampler_index.gltf": lambda g: g.doc["animations"][0]["channels"][0].update(sampler=5),
        "bad_anim_accessor_index.gltf": lambda g: slide(g).update(input=99),
        # PF_ERR_PARSE
        "bad_anim_times_order.gltf": lambda g: set_bytes(g, slide(g)["input"], [0.0, 1.0, 1.0]),
        "bad_anim_interp.gltf": lambda g: slide(g).update(interpolation="SMOOTH"),
        "bad_anim_path.gltf": lambda g: g.doc["animations"][0]["channels"][0]["target"].update(path="colour"),
        "bad_anim_twice.gltf": lambda g: g.doc["animations"][0]["channels"].append(
            copy.deepcopy(g.doc["animations"][0]["channels"][0])),
        # PF_ERR_NONFINITE
        "bad_anim_times_nan.gltf": lambda g: set_bytes(g, slide(g)["input"], [0.0, NAN, 2.0]),
        "bad_anim_times_negative.gltf": lambda g: set_bytes(g, slide(g)["input"], [-1.0, 1.0, 2.0]),
        "bad_anim_times_huge.gltf": lambda g: set_bytes(g, slide(g)["input"], [0.0, 1.0, 2.0e6]),
        "bad_anim_key_nan.gltf": lambda g: set_bytes(g, slide(g)["output"], [0.0, 0.0, 0.0, NAN]),
        "bad_anim_key_inf.gltf": lambda g: set_bytes(g, slide(g)["output"], [0.0, 0.0, float("inf")]),
        "bad_anim_rot_zero.gltf": lambda g: set_bytes(
            g, g.doc["animations"][1]["samplers"][0]["output"], [0.0, 0.0, 0.0, 0.0]),
        # PF_ERR_ACCESSOR: 3 keys, 2 values
        "bad_anim_count.gltf": lambda g: g.doc["accessors"][slide(g)["output"]].update(count=2),
        # a translation read from a VEC4 accessor
        "bad_anim_type.gltf": lambda g: slide(g).update(output=g.doc["animations"][1]["samplers"][0]["output"]),
        # PF_ERR_ACCESSOR: a huge key count without data (the implicit-element limit), and one
        # beyond the accessor limit
        "bad_anim_huge_keys.gltf": lambda g: g.doc["accessors"].append(
            {"componentType": FLOAT, "count": 1 << 26, "type": "SCALAR"}) or slide(g).update(
            input=len(g.doc["accessors"]) - 1),
        "bad_anim_limit_keys.gltf": lambda g: g.doc["accessors"].append(
            {"componentType": FLOAT, "count": (1 << 28) + 1, "type": "SCALAR"}) or slide(g).update(
            input=len(g.doc["accessors"]) - 1),
    }
    for name, mut in sorted(cases.items()):
        w.gltf("anim/" + name, lin(mut))

    # CUBICSPLINE with 2 keys and 2 values (it needs 6): PF_ERR_ACCESSOR
    g = mt.Gltf()
    g.node(mesh=g.mesh([tri_prim(g)]))
    animation(g, "c", [(0, 0, "translation")],
              [sampler(g, [0.0, 1.0], [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0)], "VEC3", "CUBICSPLINE")])
    w.gltf("anim/bad_anim_cubic_count.gltf", g)

    # a channel animating a node that has a matrix: PF_ERR_PARSE
    g = mt.Gltf()
    g.node(mesh=g.mesh([tri_prim(g)]), matrix=[1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0])
    animation(g, "m", [(0, 0, "translation")],
              [sampler(g, [0.0, 1.0], [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0)], "VEC3")])
    w.gltf("anim/bad_anim_matrix.gltf", g)

    def skin(mut):
        g = skin_file()
        mut(g)
        return g

    prim = lambda g: g.doc["meshes"][0]["primitives"][0]  # noqa: E731
    skin_cases = {
        # PF_ERR_INDEX_RANGE: JOINTS_1 names joint 5 of a 2-joint skin (vertex 4)
        "bad_skin_joint_range.gltf": lambda g: g.bin.__setitem__(
            slice(g.doc["bufferViews"][g.doc["accessors"][prim(g)["attributes"]["JOINTS_1"]]["bufferView"]][
                "byteOffset"] + 32, g.doc["bufferViews"][g.doc["accessors"][prim(g)["attributes"]["JOINTS_1"]][
                "bufferView"]]["byteOffset"] + 34), struct.pack("<H", 5)),
        "bad_skin_node_index.gltf": lambda g: g.doc["skins"][0].update(joints=[0, 42]),
        "bad_skin_index.gltf": lambda g: g.doc["nodes"][2].update(skin=3),
        "bad_skin_ibm_index.gltf": lambda g: g.doc["skins"][0].update(inverseBindMatrices=77),
        # PF_ERR_ACCESSOR
        "bad_skin_no_joints.gltf": lambda g: [prim(g)["attributes"].pop(k) for k in
                                              ("JOINTS_0", "WEIGHTS_0", "JOINTS_1", "WEIGHTS_1")],
        "bad_skin_no_weights.gltf": lambda g: prim(g)["attributes"].pop("WEIGHTS_1"),
        "bad_skin_ibm_count.gltf": lambda g: g.doc["accessors"][g.doc["skins"][0]["inverseBindMatrices"]].update(
            count=1),
        "bad_skin_joints_normalized.gltf": lambda g: g.doc["accessors"][prim(g)["attributes"]["JOINTS_0"]].update(
            normalized=True),
        # PF_ERR_NONFINITE
        "bad_skin_ibm_nan.gltf": lambda g: set_bytes(g, g.doc["skins"][0]["inverseBindMatrices"], [NAN]),
        "bad_skin_weight_nan.gltf": lambda g: set_bytes(g, prim(g)["attributes"]["WEIGHTS_1"], [NAN]),
        # PF_ERR_PARSE: a joint outside the scene; a skin without joints
        "bad_skin_joint_outside.gltf": lambda g: g.doc["scenes"][0].update(nodes=[2]) or g.doc["nodes"][0].pop(
            "children"),
        "bad_skin_empty.gltf": lambda g: g.doc["skins"][0].update(joints=[]),
    }
    for name, mut in sorted(skin_cases.items()):
        w.gltf("anim/" + name, skin(mut))

    def morph(mut):
        g = morph_file()
        mut(g)
        return g

    mprim = lambda g: g.doc["meshes"][0]["primitives"][0]  # noqa: E731
    morph_cases = {
        # PF_ERR_PARSE: node weights with 3 numbers for 2 targets; mesh weights likewise;
        # two primitives with different target counts; weights animated on a node without targets
        "bad_morph_node_weights.gltf": lambda g: g.doc["nodes"][1].update(weights=[0.0, 1.0, 0.0]),
        "bad_morph_mesh_weights.gltf": lambda g: g.doc["meshes"][0].update(weights=[0.5]),
        "bad_morph_mismatch.gltf": lambda g: g.doc["meshes"][0]["primitives"].append(
            {"attributes": dict(mprim(g)["attributes"]), "targets": [mprim(g)["targets"][0]]}),
        "bad_morph_no_targets.gltf": lambda g: [p.pop("targets") for p in g.doc["meshes"][0]["primitives"]] and
        g.doc["meshes"][0].pop("weights") and g.doc["nodes"][1].pop("weights"),
        # PF_ERR_ACCESSOR: the weights channel has 2 keys x 1 number for 2 targets
        "bad_morph_channel_count.gltf": lambda g: g.doc["accessors"][
            g.doc["animations"][0]["samplers"][0]["output"]].update(count=2),
        # PF_ERR_NONFINITE: a NaN morph delta; a NaN animated weight
        "bad_morph_delta_nan.gltf": lambda g: set_bytes(g, mprim(g)["targets"][0]["POSITION"], [0.0, NAN]),
        "bad_morph_weight_nan.gltf": lambda g: set_bytes(g, g.doc["animations"][0]["samplers"][0]["output"],
                                                         [0.0, 0.0, NAN]),
        # PF_ERR_INDEX_RANGE: a target's POSITION accessor out of range
        "bad_morph_accessor.gltf": lambda g: mprim(g)["targets"][0].update(POSITION=55),
    }
    for name, mut in sorted(morph_cases.items()):
        w.gltf("anim/" + name, morph(mut))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    outdir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "tests", "data", "gltf")
    w = mt.Writer(os.path.normpath(outdir))
    w.gltf("anim/anim_linear.gltf", linear_file())
    w.gltf("anim/anim_cubic.gltf", cubic_file())
    w.gltf("anim/anim_skin.gltf", skin_file())
    w.gltf("anim/anim_morph.gltf", morph_file())
    w.gltf("anim/anim_hierarchy.gltf", hierarchy_file())
    w.gltf("anim/anim_far.gltf", far_file())
    bad_files(w)
    print("wrote %d files to %s" % (len(w.written), os.path.join(w.outdir, "anim")))


if __name__ == "__main__":
    main()
