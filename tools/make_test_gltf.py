#!/usr/bin/env python3
"""make_test_gltf: writes the small authored glTF files that tests/test_gltf_loader.c
checks, into tests/data/gltf/ (standard library only, deterministic bytes).

Every good file exercises one loader feature with values chosen so the expected
world-space result is exact or nearly so (90-degree rotations, powers of two).
Every bad file (bad_*) breaks exactly one rule the loader must catch. The test
file lists the expected numbers next to each case; change both together.

Usage: python3 tools/make_test_gltf.py [OUTPUT_DIR]
"""
import base64
import json
import math
import os
import struct
import sys
import zlib

# glTF constants (glTF 2.0 spec, 5.1 and 5.26)
BYTE, UBYTE, SHORT, USHORT, UINT, FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
POINTS, LINES, TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN = 0, 1, 4, 5, 6
NEAREST, LINEAR = 9728, 9729
NEAREST_MIPMAP_NEAREST, LINEAR_MIPMAP_NEAREST = 9984, 9985
NEAREST_MIPMAP_LINEAR, LINEAR_MIPMAP_LINEAR = 9986, 9987
REPEAT, CLAMP, MIRROR = 10497, 33071, 33648

S = math.sqrt(0.5)  # sin(45 deg) = cos(45 deg): quaternion of a 90-degree turn

# The 2x2 RGBA test image (row 0 is the top of the image = v in [0, 0.5)).
#   (0,0) red opaque     (1,0) green, alpha 128
#   (0,1) blue opaque    (1,1) sRGB grey 128 opaque
CHECKER_RGBA = [
    [(255, 0, 0, 255), (0, 255, 0, 128)],
    [(0, 0, 255, 255), (128, 128, 128, 255)],
]


def png(w, h, color_type, bit_depth, row_bytes, extra_chunks=()):
    """Minimal PNG written with zlib + struct: filter 0 on every row, the rows
    given already packed (row_bytes[y] is the scanline without its filter byte)."""

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + bytes(r) for r in row_bytes)
    ihdr = struct.pack(">IIBBBBB", w, h, bit_depth, color_type, 0, 0, 0)
    out = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr)
    for tag, data in extra_chunks:
        out += chunk(tag, data)
    return out + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")


def png_rgba(rows):
    """RGBA8 PNG of rows of (r, g, b, a) tuples."""
    return png(len(rows[0]), len(rows), 6, 8, [b"".join(bytes(px) for px in row) for row in rows])


CHECKER_PNG = png_rgba(CHECKER_RGBA)


def f32(values):
    return struct.pack("<%df" % len(values), *values)


def flat(vecs):
    return [c for v in vecs for c in v]


class Gltf:
    """Accumulates one binary buffer and the JSON that describes it."""

    def __init__(self):
        self.bin = bytearray()
        self.doc = {"asset": {"version": "2.0", "generator": "softgi tools/make_test_gltf.py"}}

    def arr(self, key):
        return self.doc.setdefault(key, [])

    def add(self, key, obj):
        a = self.arr(key)
        a.append(obj)
        return len(a) - 1

    def view(self, data, stride=None, target=None, length=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data) if length is None else length}
        if stride is not None:
            v["byteStride"] = stride
        if target is not None:
            v["target"] = target
        self.bin += data
        return self.add("bufferViews", v)

    def accessor(self, view, ctype, count, atype, normalized=False, offset=0, minv=None, maxv=None, sparse=None):
        a = {}
        if view is not None:
            a["bufferView"] = view
        if offset:
            a["byteOffset"] = offset
        a["componentType"] = ctype
        if normalized:
            a["normalized"] = True
        a["count"] = count
        a["type"] = atype
        if minv is not None:
            a["min"] = minv
            a["max"] = maxv
        if sparse is not None:
            a["sparse"] = sparse
        return self.add("accessors", a)

    def vec3(self, vecs, bounds=True):
        """Float VEC3 accessor (positions or normals) in a view of its own."""
        v = self.view(f32(flat(vecs)), target=ARRAY_BUFFER)
        mn = mx = None
        if bounds:
            mn = [min(p[i] for p in vecs) for i in range(3)]
            mx = [max(p[i] for p in vecs) for i in range(3)]
        return self.accessor(v, FLOAT, len(vecs), "VEC3", minv=mn, maxv=mx)

    def vec2(self, vecs):
        v = self.view(f32(flat(vecs)), target=ARRAY_BUFFER)
        return self.accessor(v, FLOAT, len(vecs), "VEC2")

    def indices(self, idx, ctype=USHORT):
        fmt = {UBYTE: "B", USHORT: "H", UINT: "I"}[ctype]
        v = self.view(struct.pack("<%d%s" % (len(idx), fmt), *idx), target=ELEMENT_ARRAY_BUFFER)
        return self.accessor(v, ctype, len(idx), "SCALAR")

    def prim(self, pos, nrm=None, uv=None, idx=None, material=None, mode=None):
        p = {"attributes": {"POSITION": pos}}
        if nrm is not None:
            p["attributes"]["NORMAL"] = nrm
        if uv is not None:
            p["attributes"]["TEXCOORD_0"] = uv
        if idx is not None:
            p["indices"] = idx
        if material is not None:
            p["material"] = material
        if mode is not None:
            p["mode"] = mode
        return p

    def mesh(self, prims, name=None):
        m = {"primitives": prims}
        if name:
            m["name"] = name
        return self.add("meshes", m)

    def node(self, **kw):
        return self.add("nodes", dict(kw))

    def scene(self, nodes, default=True):
        s = self.add("scenes", {"nodes": nodes})
        if default:
            self.doc["scene"] = s
        return s

    def json_doc(self, buffer_uri):
        """The document with its one buffer: a uri, or None for the GLB BIN chunk."""
        doc = dict(self.doc)
        if self.bin:
            b = {"byteLength": len(self.bin)}
            if buffer_uri is not None:
                b["uri"] = buffer_uri
            doc["buffers"] = [b]
        return doc


def dumps(doc):
    return json.dumps(doc, indent=1, allow_nan=False).encode("ascii") + b"\n"


def data_uri(data, mime="application/octet-stream"):
    return "data:%s;base64,%s" % (mime, base64.b64encode(bytes(data)).decode("ascii"))


def glb_bytes(doc, bin_data):
    js = json.dumps(doc, separators=(",", ":"), allow_nan=False).encode("ascii")
    js += b" " * ((4 - len(js) % 4) % 4)
    out = struct.pack("<4sII", b"glTF", 2, 0) + struct.pack("<I4s", len(js), b"JSON") + js
    if bin_data:
        b = bytes(bin_data) + b"\x00" * ((4 - len(bin_data) % 4) % 4)
        out += struct.pack("<I4s", len(b), b"BIN\x00") + b
    return out[:8] + struct.pack("<I", len(out)) + out[12:]


class Writer:
    def __init__(self, outdir):
        self.outdir = outdir
        self.written = []

    def raw(self, name, data):
        path = os.path.join(self.outdir, name)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(data)
        self.written.append(name)

    def gltf(self, name, g, external_bin=None):
        """Writes g as .gltf with its buffer as a data uri, or as an external .bin."""
        if external_bin:
            self.raw(external_bin, bytes(g.bin))
            doc = g.json_doc(external_bin)
        else:
            doc = g.json_doc(data_uri(g.bin) if g.bin else None)
        data = dumps(doc)
        self.raw(name, data)
        return data

    def glb(self, name, g):
        data = glb_bytes(g.json_doc(None), g.bin)
        self.raw(name, data)
        return data


TRI = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)]
UP = (0.0, 0.0, 1.0)
QUAD = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0)]
QUAD_IDX = [0, 1, 2, 0, 2, 3]


def tri_mesh(g, z=0.0, material=None, normals=True, uv=None):
    pos = g.vec3([(x, y, z) for (x, y, _) in TRI])
    nrm = g.vec3([UP] * 3, bounds=False) if normals else None
    uva = g.vec2(uv) if uv else None
    return g.mesh([g.prim(pos, nrm, uva, material=material)])


# ------------------------------------------------------------------ good files


def good_files(w):
    # triangle.gltf: one triangle, normals, no uvs, one material, explicit scene.
    g = Gltf()
    g.add("materials", {"name": "tri", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1.0, 1.0]},
                        "doubleSided": True})
    m = tri_mesh(g, material=0)
    g.scene([g.node(name="tri", mesh=m)])
    w.gltf("triangle.gltf", g)
    w.glb("triangle.glb", g)

    # quad_u8/u16/u32/noindex: the unit quad (0,0)-(1,1) at z=0, two triangles
    # 0-1-2 and 0-2-3; no "scenes" array (every root node is drawn).
    for name, ctype in (("quad_u8.gltf", UBYTE), ("quad_u16.gltf", USHORT), ("quad_u32.gltf", UINT)):
        g = Gltf()
        pos = g.vec3(QUAD)
        nrm = g.vec3([UP] * 4, bounds=False)
        idx = g.indices(QUAD_IDX, ctype)
        g.node(mesh=g.mesh([g.prim(pos, nrm, idx=idx)]))
        w.gltf(name, g)
    g = Gltf()
    corners = [QUAD[i] for i in QUAD_IDX]
    pos = g.vec3(corners)
    nrm = g.vec3([UP] * 6, bounds=False)
    g.node(mesh=g.mesh([g.prim(pos, nrm)]))
    w.gltf("quad_noindex.gltf", g)

    # hierarchy_trs.gltf: root T(10,0,0) R_z(90) S(2) -> child T(0,1,0) holds the
    # triangle: world (8,0,0) (8,2,0) (6,0,0). A second root T(0,0,5) instances
    # the same mesh: (0,0,5) (1,0,5) (0,1,5).
    g = Gltf()
    m = tri_mesh(g)
    g.node(name="root", translation=[10.0, 0.0, 0.0], rotation=[0.0, 0.0, S, S], scale=[2.0, 2.0, 2.0], children=[1])
    g.node(name="child", translation=[0.0, 1.0, 0.0], mesh=m)
    g.node(name="second", translation=[0.0, 0.0, 5.0], mesh=m)
    g.scene([0, 2])
    w.gltf("hierarchy_trs.gltf", g)

    # hierarchy_matrix.gltf: root matrix = T(0,0,-5) R_x(90) (column-major),
    # child matrix = T(1,2,3): world (1,-3,-3) (2,-3,-3) (1,-3,-2), normal (0,-1,0).
    g = Gltf()
    m = tri_mesh(g)
    g.node(name="root", matrix=[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, -5.0, 1.0],
           children=[1])
    g.node(name="child", matrix=[1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 2.0, 3.0, 1.0],
           mesh=m)
    g.scene([0])
    w.gltf("hierarchy_matrix.gltf", g)

    # negative_scale.gltf: node "mirror_x" S(-1,1,1) over the triangle with
    # normals: world (0,0,0) (-1,0,0) (0,1,0), normal stays (0,0,1), winding must
    # come back CCW about it. Node "mirror_z" S(1,1,-1) T(0,0,-3) over a
    # triangle without normals: flat normal (0,0,-1), CCW about it.
    g = Gltf()
    m0 = tri_mesh(g)
    m1 = tri_mesh(g, normals=False)
    g.node(name="mirror_x", scale=[-1.0, 1.0, 1.0], mesh=m0)
    g.node(name="mirror_z", translation=[0.0, 0.0, -3.0], scale=[1.0, 1.0, -1.0], mesh=m1)
    g.scene([0, 1])
    w.gltf("negative_scale.gltf", g)

    # flat_normals.gltf: indexed, no NORMAL; triangles 0-1-2 (normal +Z) and
    # 0-2-3 with v3=(0,1,1) (normal (1,-1,1)/sqrt3) share vertices 0 and 2,
    # which must be unwelded: 6 vertices.
    g = Gltf()
    pos = g.vec3([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 1.0)])
    idx = g.indices(QUAD_IDX, USHORT)
    g.node(mesh=g.mesh([g.prim(pos, idx=idx)]))
    w.gltf("flat_normals.gltf", g)

    # normals_nonuniform.gltf: triangle (1,0,0) (0,1,0) (1,0,1) in the plane
    # x+y=1 with normal (1,1,0)/sqrt2, under S(2,1,1): world (2,0,0) (0,1,0)
    # (2,0,1), plane x/2+y=1, normal (1,2,0)/sqrt5 (inverse transpose).
    g = Gltf()
    pos = g.vec3([(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.0, 0.0, 1.0)])
    nrm = g.vec3([(S, S, 0.0)] * 3, bounds=False)
    g.node(scale=[2.0, 1.0, 1.0], mesh=g.mesh([g.prim(pos, nrm)]))
    w.gltf("normals_nonuniform.gltf", g)

    # texcoords.gltf: three triangles (z = 0, 1, 2) with TEXCOORD_0 as float,
    # normalized u8 (byteStride 4) and normalized u16.
    g = Gltf()
    prims = []
    p = g.vec3([(x, y, 0.0) for (x, y, _) in TRI])
    prims.append(g.prim(p, uv=g.vec2([(0.25, 0.5), (0.75, 0.5), (0.5, 1.0)])))
    p = g.vec3([(x, y, 1.0) for (x, y, _) in TRI])
    u8 = bytes([0, 255, 0, 0, 255, 51, 0, 0, 51, 0, 0, 0])  # (0,1) (1,0.2) (0.2,0), 2 bytes pad each
    prims.append(g.prim(p, uv=g.accessor(g.view(u8, stride=4, target=ARRAY_BUFFER), UBYTE, 3, "VEC2", normalized=True)))
    p = g.vec3([(x, y, 2.0) for (x, y, _) in TRI])
    u16 = struct.pack("<6H", 0, 65535, 65535, 32768, 32768, 0)  # (0,1) (1,32768/65535) (32768/65535,0)
    prims.append(g.prim(p, uv=g.accessor(g.view(u16, target=ARRAY_BUFFER), USHORT, 3, "VEC2", normalized=True)))
    g.node(mesh=g.mesh(prims))
    w.gltf("texcoords.gltf", g)

    # texture_datauri.gltf: the 2x2 checker as a data uri image, shared by six
    # textures with different samplers; material i is drawn by a triangle at z=i.
    g = Gltf()
    g.add("images", {"uri": data_uri(CHECKER_PNG, "image/png")})
    samplers = [
        ("repeat_nearest", {"magFilter": NEAREST, "minFilter": NEAREST, "wrapS": REPEAT, "wrapT": REPEAT}),
        ("clamp_nearest", {"magFilter": NEAREST, "minFilter": NEAREST, "wrapS": CLAMP, "wrapT": CLAMP}),
        ("mirror_nearest", {"magFilter": NEAREST, "minFilter": NEAREST, "wrapS": MIRROR, "wrapT": MIRROR}),
        ("linear_mips", {"magFilter": LINEAR, "minFilter": LINEAR_MIPMAP_LINEAR}),
        ("default_sampler", None),
        ("mixed", {"magFilter": NEAREST, "minFilter": NEAREST_MIPMAP_NEAREST, "wrapS": CLAMP, "wrapT": MIRROR}),
        ("lin_mip_nearest", {"minFilter": LINEAR_MIPMAP_NEAREST}),
        ("near_mip_linear", {"minFilter": NEAREST_MIPMAP_LINEAR}),
    ]
    prims = []
    for i, (name, smp) in enumerate(samplers):
        t = {"source": 0}
        if smp is not None:
            t["sampler"] = g.add("samplers", smp)
        tex = g.add("textures", t)
        factor = [1.0, 0.5, 1.0, 1.0] if i == 0 else [1.0, 1.0, 1.0, 1.0]
        g.add("materials", {"name": name, "pbrMetallicRoughness": {"baseColorFactor": factor,
                                                                    "baseColorTexture": {"index": tex}}})
        p = g.vec3([(x, y, float(i)) for (x, y, _) in TRI])
        prims.append(g.prim(p, uv=g.vec2([(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]), material=i))
    g.node(mesh=g.mesh(prims))
    w.gltf("texture_datauri.gltf", g)

    # texture_bufferview.gltf / .glb: the checker stored in a bufferView
    # (mimeType image/png), NEAREST, one triangle with uvs.
    g = Gltf()
    p = g.vec3(TRI)
    uv = g.vec2([(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])
    g.add("images", {"bufferView": g.view(CHECKER_PNG), "mimeType": "image/png"})
    g.add("samplers", {"magFilter": NEAREST, "minFilter": NEAREST})
    g.add("textures", {"source": 0, "sampler": 0})
    g.add("materials", {"name": "checker", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})
    g.node(mesh=g.mesh([g.prim(p, uv=uv, material=0)]))
    w.gltf("texture_bufferview.gltf", g)
    w.glb("texture_bufferview.glb", g)

    # texture_external.gltf: external .bin and external checker.png.
    g = Gltf()
    p = g.vec3(TRI)
    uv = g.vec2([(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])
    g.add("images", {"uri": "checker.png"})
    g.add("samplers", {"magFilter": NEAREST, "minFilter": NEAREST})
    g.add("textures", {"source": 0, "sampler": 0})
    g.add("materials", {"name": "checker", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})
    g.node(mesh=g.mesh([g.prim(p, uv=uv, material=0)]))
    w.raw("checker.png", CHECKER_PNG)
    w.gltf("texture_external.gltf", g, external_bin="texture_external.bin")

    # alpha_mask.gltf: MASK with cutoff 0.25 (alpha 0.75), MASK with the default cutoff, BLEND,
    # OPAQUE double-sided; triangle i uses material i at z=i.
    g = Gltf()
    mats = [
        {"name": "mask_025", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 0.75]}, "alphaMode": "MASK",
         "alphaCutoff": 0.25},
        {"name": "mask_default", "alphaMode": "MASK"},
        {"name": "blend", "alphaMode": "BLEND"},
        {"name": "opaque_double", "doubleSided": True},
    ]
    prims = []
    for i, m in enumerate(mats):
        g.add("materials", m)
        prims.append(g.prim(g.vec3([(x, y, float(i)) for (x, y, _) in TRI]), material=i))
    g.node(mesh=g.mesh(prims))
    w.gltf("alpha_mask.gltf", g)

    # emissive.gltf: emissiveFactor x KHR_materials_emissive_strength.
    g = Gltf()
    g.doc["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    mats = [
        {"name": "strong", "emissiveFactor": [1.0, 0.5, 0.25],
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}},
        {"name": "plain", "emissiveFactor": [0.5, 0.25, 0.125]},
        {"name": "dark"},
    ]
    prims = []
    for i, m in enumerate(mats):
        g.add("materials", m)
        prims.append(g.prim(g.vec3([(x, y, float(i)) for (x, y, _) in TRI]), material=i))
    g.node(mesh=g.mesh(prims))
    w.gltf("emissive.gltf", g)

    # default_material.gltf: a red material at z=0 and a primitive without
    # material at z=1 (glTF default: white, opaque, single-sided, no emission).
    g = Gltf()
    g.add("materials", {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 1.0]}})
    prims = [g.prim(g.vec3(TRI), material=0), g.prim(g.vec3([(x, y, 1.0) for (x, y, _) in TRI]))]
    g.node(mesh=g.mesh(prims))
    w.gltf("default_material.gltf", g)

    # camera.gltf: perspective camera "main_cam" in child T(0,0,5) of parent
    # T(1,2,3) R_y(90): eye (6,2,3), forward (-1,0,0), up (0,1,0), right (0,0,-1).
    # An orthographic camera is skipped with a warning.
    g = Gltf()
    g.add("cameras", {"name": "main_cam", "type": "perspective",
                      "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100.0, "aspectRatio": 1.5}})
    g.add("cameras", {"name": "ortho_cam", "type": "orthographic",
                      "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.1, "zfar": 10.0}})
    m = tri_mesh(g)
    g.node(name="cam_parent", translation=[1.0, 2.0, 3.0], rotation=[0.0, S, 0.0, S], children=[1])
    g.node(name="main_cam", translation=[0.0, 0.0, 5.0], camera=0)
    g.node(name="ortho_cam", camera=1)
    g.node(name="mesh", mesh=m)
    g.scene([0, 2, 3])
    w.gltf("camera.gltf", g)

    # lights.gltf: KHR_lights_punctual; light and node share each name.
    g = Gltf()
    g.doc["extensionsUsed"] = ["KHR_lights_punctual"]
    g.doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "bulb", "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 10.0, "range": 5.0},
        {"name": "spot", "type": "spot", "color": [1.0, 1.0, 1.0], "intensity": 20.0,
         "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.5}},
        {"name": "sun", "type": "directional", "color": [0.5, 0.5, 1.0], "intensity": 3.0},
        {"name": "bulb_default", "type": "point"},
        {"name": "spot_default", "type": "spot", "spot": {}},
    ]}}
    m = tri_mesh(g)

    def light(i):
        return {"KHR_lights_punctual": {"light": i}}

    g.node(name="bulb", translation=[1.0, 2.0, 3.0], extensions=light(0))             # 0
    g.node(name="spot", translation=[0.0, 5.0, 0.0], rotation=[-S, 0.0, 0.0, S],      # 1: -Z -> -Y
           extensions=light(1))
    g.node(name="sun_parent", translation=[100.0, 0.0, 0.0], rotation=[0.0, S, 0.0, S],  # 2: -Z -> -X
           scale=[3.0, 3.0, 3.0], children=[3])
    g.node(name="sun", extensions=light(2))                                            # 3
    g.node(name="bulb_default", translation=[0.0, 0.0, -2.0], extensions=light(3))     # 4
    g.node(name="spot_default", translation=[4.0, 0.0, 0.0], extensions=light(4))      # 5: -Z
    g.node(name="mesh", mesh=m)                                                        # 6
    g.scene([0, 1, 2, 4, 5, 6])
    w.gltf("lights.gltf", g)

    # strip_fan.gltf: an indexed TRIANGLE_STRIP of 5 vertices (3 triangles, all
    # CCW about +Z), a non-indexed TRIANGLE_FAN of 4 vertices around (5,0,0)
    # (2 triangles, no normals) and a POINTS primitive (skipped, warned).
    g = Gltf()
    sv = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (1.0, 1.0, 0.0), (0.0, 2.0, 0.0)]
    strip = g.prim(g.vec3(sv), g.vec3([UP] * 5, bounds=False), idx=g.indices([0, 1, 2, 3, 4], USHORT),
                   mode=TRIANGLE_STRIP)
    fv = [(5.0, 0.0, 0.0), (6.0, 0.0, 0.0), (6.0, 1.0, 0.0), (5.0, 1.0, 0.0)]
    fan = g.prim(g.vec3(fv), mode=TRIANGLE_FAN)
    pts = g.prim(g.vec3([(9.0, 9.0, 9.0)]), mode=POINTS)
    g.node(mesh=g.mesh([strip, fan, pts]))
    w.gltf("strip_fan.gltf", g)

    # texture_formats.gltf: 2x2 PNGs in other layouts, each converted to RGBA8
    # at load; triangle i (z = i) uses image i (NEAREST). Expected level-0
    # texels are listed in test_gltf_loader.c.
    g = Gltf()
    ck = CHECKER_RGBA
    formats = [
        ("grey8", png(2, 2, 0, 8, [bytes([0, 64]), bytes([128, 255])])),
        ("rgb8", png(2, 2, 2, 8, [b"".join(bytes(px[:3]) for px in row) for row in ck])),
        ("grey_alpha8", png(2, 2, 4, 8, [bytes([0, 255, 64, 128]), bytes([128, 0, 255, 255])])),
        ("rgba16", png(2, 2, 6, 16, [b"".join(struct.pack(">4H", *[c * 257 for c in px]) for px in row)
                                     for row in ck])),
        ("palette_trns", png(2, 2, 3, 8, [bytes([0, 1]), bytes([2, 3])],
                             [(b"PLTE", bytes([255, 0, 0, 0, 255, 0, 0, 0, 255, 128, 128, 128])),
                              (b"tRNS", bytes([255, 128]))])),
        ("grey1", png(2, 2, 0, 1, [bytes([0x40]), bytes([0x80])])),
    ]
    smp = g.add("samplers", {"magFilter": NEAREST, "minFilter": NEAREST})
    prims = []
    for i, (name, data) in enumerate(formats):
        img = g.add("images", {"name": name, "uri": data_uri(data, "image/png")})
        tex = g.add("textures", {"source": img, "sampler": smp})
        g.add("materials", {"name": name, "pbrMetallicRoughness": {"baseColorTexture": {"index": tex}}})
        p = g.vec3([(x, y, float(i)) for (x, y, _) in TRI])
        prims.append(g.prim(p, uv=g.vec2([(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]), material=i))
    g.node(mesh=g.mesh(prims))
    w.gltf("texture_formats.gltf", g)

    # interleaved.gltf: the unit quad with POSITION, NORMAL and TEXCOORD_0
    # interleaved in one bufferView (byteStride 32, byteOffsets 0/12/24), u16
    # indices; uv = (x, 1 - y).
    g = Gltf()
    inter = b"".join(f32([x, y, z, 0.0, 0.0, 1.0, x, 1.0 - y]) for (x, y, z) in QUAD)
    iv = g.view(inter, stride=32, target=ARRAY_BUFFER)
    pa = g.accessor(iv, FLOAT, 4, "VEC3", minv=[0.0, 0.0, 0.0], maxv=[1.0, 1.0, 0.0])
    na = g.accessor(iv, FLOAT, 4, "VEC3", offset=12)
    ua = g.accessor(iv, FLOAT, 4, "VEC2", offset=24)
    g.node(mesh=g.mesh([g.prim(pa, na, ua, idx=g.indices(QUAD_IDX, USHORT))]))
    w.gltf("interleaved.gltf", g)

    # normals_unnormalized.gltf: NORMALs (0,0,2), (0,0,1e-3), (0,0,3e-23) on a
    # +Z triangle: all must come out as the unit (0,0,1). (3e-23 squared is
    # below the smallest float denormal: a float-only normalisation gets it wrong.)
    g = Gltf()
    pos = g.vec3(TRI)
    nrm = g.vec3([(0.0, 0.0, 2.0), (0.0, 0.0, 1e-3), (0.0, 0.0, 3e-23)], bounds=False)
    g.node(mesh=g.mesh([g.prim(pos, nrm)]))
    w.gltf("normals_unnormalized.gltf", g)

    # sparse.gltf: primitive 0 positions = TRI with vertex 2 replaced by
    # (0,3,0) through a sparse accessor (u8 indices); primitive 1 positions come
    # from a sparse accessor without bufferView (zeros) with vertices 1 and 2
    # set: (0,0,0) (1,0,5) (0,1,5).
    g = Gltf()
    base = g.view(f32(flat(TRI)), target=ARRAY_BUFFER)
    si = g.view(bytes([2]))
    sval = g.view(f32([0.0, 3.0, 0.0]))
    a0 = g.accessor(base, FLOAT, 3, "VEC3", minv=[0.0, 0.0, 0.0], maxv=[1.0, 3.0, 0.0],
                    sparse={"count": 1, "indices": {"bufferView": si, "componentType": UBYTE},
                            "values": {"bufferView": sval}})
    si2 = g.view(struct.pack("<2H", 1, 2))
    sval2 = g.view(f32([1.0, 0.0, 5.0, 0.0, 1.0, 5.0]))
    a1 = g.accessor(None, FLOAT, 3, "VEC3", minv=[0.0, 0.0, 0.0], maxv=[1.0, 1.0, 5.0],
                    sparse={"count": 2, "indices": {"bufferView": si2, "componentType": USHORT},
                            "values": {"bufferView": sval2}})
    g.node(mesh=g.mesh([g.prim(a0), g.prim(a1)]))
    w.gltf("sparse.gltf", g)

    # degenerate.gltf: 5 triangles, 2 good: 0-1-2 and 1-4-2; dropped: 0-0-1
    # (repeated index), 0-1-3 (collinear), 0-5-1 (v5 == v0 in position).
    g = Gltf()
    dv = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (2.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 0.0, 0.0)]
    di = [0, 1, 2, 0, 0, 1, 0, 1, 3, 1, 4, 2, 0, 5, 1]
    g.node(mesh=g.mesh([g.prim(g.vec3(dv), g.vec3([UP] * 6, bounds=False), idx=g.indices(di, USHORT))]))
    w.gltf("degenerate.gltf", g)

    # scene_select.gltf: scene 0 holds a triangle at z=0, the default scene 1 a
    # triangle at z=7: only the latter is loaded.
    g = Gltf()
    m0 = tri_mesh(g)
    m1 = tri_mesh(g, z=7.0)
    g.node(mesh=m0)
    g.node(mesh=m1)
    g.scene([0], default=False)
    g.scene([1])
    w.gltf("scene_select.gltf", g)


# ------------------------------------------------------------------ bad files


def bad_files(w, glb_good, gltf_good):
    # Truncations: half of a good .glb; a .gltf cut inside its JSON.
    w.raw("bad_truncated.glb", glb_good[: len(glb_good) // 2])
    w.raw("bad_truncated.gltf", gltf_good[: len(gltf_good) * 2 // 3])

    # Malformed JSON: a missing closing brace and a trailing comma.
    w.raw("bad_json.gltf", b'{"asset": {"version": "2.0"}, "nodes": [{"mesh": 0},]\n')

    # Accessor 1 (NORMAL, 3 x 12 bytes) in bufferView 1 of only 24 bytes.
    g = Gltf()
    p = g.vec3(TRI)
    nv = g.view(f32(flat([UP] * 2)), target=ARRAY_BUFFER)
    n = g.accessor(nv, FLOAT, 3, "VEC3")
    g.node(mesh=g.mesh([g.prim(p, n)]))
    w.gltf("bad_accessor_past_view.gltf", g)

    # bufferView 1 claims 48 bytes at offset 36 of a 72-byte buffer.
    g = Gltf()
    p = g.vec3(TRI)
    nv = g.view(f32(flat([UP] * 3)), target=ARRAY_BUFFER, length=48)
    n = g.accessor(nv, FLOAT, 3, "VEC3")
    g.node(mesh=g.mesh([g.prim(p, n)]))
    w.gltf("bad_view_past_buffer.gltf", g)

    # Index 77 into 3 vertices.
    g = Gltf()
    p = g.vec3(TRI)
    g.node(mesh=g.mesh([g.prim(p, idx=g.indices([0, 1, 77], USHORT))]))
    w.gltf("bad_index_range.gltf", g)

    # Non-finite and huge positions (bytes written directly: JSON has no NaN).
    for name, bad in (("bad_nan.gltf", float("nan")), ("bad_inf.gltf", float("inf")), ("bad_huge.gltf", 1.0e30)):
        g = Gltf()
        v = g.view(f32([0.0, 0.0, 0.0, bad, 0.0, 0.0, 0.0, 1.0, 0.0]), target=ARRAY_BUFFER)
        g.node(mesh=g.mesh([g.prim(g.accessor(v, FLOAT, 3, "VEC3"))]))
        w.gltf(name, g)

    # Huge only after the node transform: S(1e30) over the unit triangle.
    g = Gltf()
    g.node(scale=[1.0e30, 1.0e30, 1.0e30], mesh=tri_mesh(g))
    w.gltf("bad_huge_transform.gltf", g)

    # Node cycles: 0 -> 1 -> 0, and a node that is its own child.
    g = Gltf()
    m = tri_mesh(g)
    g.node(name="a", children=[1], mesh=m)
    g.node(name="b", children=[0])
    g.scene([0])
    w.gltf("bad_cycle.gltf", g)
    g = Gltf()
    m = tri_mesh(g)
    g.node(name="self", children=[0], mesh=m)
    g.scene([0])
    w.gltf("bad_self_cycle.gltf", g)

    # External .bin that does not exist (the document is otherwise fine).
    g = Gltf()
    g.node(mesh=tri_mesh(g))
    doc = g.json_doc("does_not_exist.bin")
    w.raw("bad_missing_bin.gltf", dumps(doc))

    # Image file that does not exist.
    g = Gltf()
    p = g.vec3(TRI)
    uv = g.vec2([(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])
    g.add("images", {"uri": "missing_texture.png"})
    g.add("textures", {"source": 0})
    g.add("materials", {"name": "lost", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})
    g.node(mesh=g.mesh([g.prim(p, uv=uv, material=0)]))
    w.gltf("bad_missing_texture.gltf", g)

    # Nothing to render: points only; only zero-area triangles.
    g = Gltf()
    g.node(mesh=g.mesh([g.prim(g.vec3(TRI), mode=POINTS)]))
    w.gltf("bad_only_points.gltf", g)
    g = Gltf()
    p = g.vec3([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (2.0, 0.0, 0.0)])
    g.node(mesh=g.mesh([g.prim(p, idx=g.indices([0, 1, 2, 0, 0, 1], USHORT))]))
    w.gltf("bad_only_degenerate.gltf", g)

    # Object references out of range: mesh 5 of 1, material 3 of 1,
    # POSITION accessor 9 of 1, bufferView 4 of 1, texture 6 of 0.
    g = Gltf()
    tri_mesh(g)
    g.node(mesh=5)
    w.gltf("bad_mesh_index.gltf", g)
    g = Gltf()
    g.add("materials", {"name": "only"})
    g.node(mesh=tri_mesh(g, material=3))
    w.gltf("bad_material_index.gltf", g)
    g = Gltf()
    p = g.vec3(TRI)
    g.node(mesh=g.mesh([g.prim(9)]))
    w.gltf("bad_accessor_index.gltf", g)
    g = Gltf()
    g.vec3(TRI)
    g.doc["accessors"][0]["bufferView"] = 4
    g.node(mesh=g.mesh([g.prim(0)]))
    w.gltf("bad_bufferview_index.gltf", g)
    g = Gltf()
    g.add("materials", {"name": "tex6", "pbrMetallicRoughness": {"baseColorTexture": {"index": 6}}})
    g.node(mesh=tri_mesh(g, material=0, uv=[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)]))
    w.gltf("bad_texture_index.gltf", g)

    # Nodes with more than one parent (glTF 2.0 Sec. 3.5.3: the hierarchy is a
    # set of disjoint trees): node k lists node k+1 twice, 24 levels deep, so a
    # walk that does not notice visits 2^24 paths (at 40 levels, 2^40: a hang).
    g = Gltf()
    g.node(mesh=tri_mesh(g), children=[1, 1])
    for k in range(1, 24):
        g.node(children=[k + 1, k + 1])
    g.node()
    g.scene([0])
    w.gltf("bad_dag.gltf", g)

    # KHR_lights_punctual light index 1e30 (not an int: converting it is UB).
    g = Gltf()
    g.doc["extensionsUsed"] = ["KHR_lights_punctual"]
    g.doc["extensions"] = {"KHR_lights_punctual": {"lights": [{"name": "only", "type": "point"}]}}
    g.node(mesh=tri_mesh(g))
    g.node(extensions={"KHR_lights_punctual": {"light": 1e30}})
    w.gltf("bad_light_index.gltf", g)

    # An external image that sits in the working directory of the test
    # (tests/data/gltf) but not next to this file (subdir/): uris resolve
    # against the file's directory only.
    g = Gltf()
    p = g.vec3(TRI)
    uv = g.vec2([(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])
    g.add("images", {"uri": "checker.png"})
    g.add("textures", {"source": 0})
    g.add("materials", {"name": "elsewhere", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}})
    g.node(mesh=g.mesh([g.prim(p, uv=uv, material=0)]))
    w.gltf("subdir/bad_texture_not_beside.gltf", g)

    # POSITION with a byteStride (4) smaller than the element (12 bytes).
    g = Gltf()
    v = g.view(f32(flat(TRI)), stride=4, target=ARRAY_BUFFER)
    g.node(mesh=g.mesh([g.prim(g.accessor(v, FLOAT, 3, "VEC3"))]))
    w.gltf("bad_stride.gltf", g)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    outdir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "tests", "data", "gltf")
    w = Writer(os.path.normpath(outdir))
    good_files(w)
    with open(os.path.join(w.outdir, "texture_bufferview.glb"), "rb") as f:
        glb_good = f.read()
    with open(os.path.join(w.outdir, "triangle.gltf"), "rb") as f:
        gltf_good = f.read()
    bad_files(w, glb_good, gltf_good)
    print("wrote %d files to %s" % (len(w.written), w.outdir))


if __name__ == "__main__":
    main()
