#!/usr/bin/env python3
"""make_scenes: writes softgi's small authored glTF 2.0 scenes.

Usage:  python3 tools/make_scenes.py [output_root]      (default: the repository root)

Writes, each as one self-contained .gltf (geometry in an embedded base64 data-URI buffer):
  scenes/cornell-box/cornell-box.gltf      the Cornell Program of Computer Graphics measured box
  scenes/closed-sphere/closed-sphere.gltf  inward-facing emissive icosphere (furnace test)
  scenes/box-room-hole/box-room-hole.gltf  closed room lit by the sun through one window
  scenes/maze/maze.gltf                    8 x 8 maze of thin wall boxes (heavy occlusion)
  scenes/corridor/corridor.gltf            two rooms joined by a Z-shaped corridor (indirect visibility)

Conventions (softgi README "Light units", src/scene/pf_scene.h): right-handed world, +Y up,
metres. KHR_lights_punctual point/spot intensity is radiant intensity in W/sr (E = I cos(theta) / r^2),
directional intensity is irradiance in W/m^2. Materials are Lambertian, albedo = baseColorFactor
(linear RGB). Every triangle is counter-clockwise seen from its front (the side its NORMAL points
to) and every primitive carries explicit NORMALs that agree with its winding.

Determinism: only IEEE-exact arithmetic (+, -, *, /, sqrt) reaches the buffers; the two places that
need a transcendental function (the spectral-to-RGB fit, the Cornell field of view) round the result
far above the last-ulp differences between libms. Same input, same bytes. tests/test_scenes.c checks
the invariants this file promises (counts, bounds, albedos, closedness, winding).

Standard library only: no numpy, so anyone with Python 3 can regenerate the files.
"""
import base64
import json
import math
import os
import struct
import sys

GENERATOR = "softgi tools/make_scenes.py"

# --------------------------------------------------------------------------------------------
# Small vector helpers (tuples of Python floats, i.e. doubles)


def v_add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def v_sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def v_scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def v_dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def v_cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def v_normalize(a):
    length = math.sqrt(v_dot(a, a))
    assert length > 0.0
    return (a[0] / length, a[1] / length, a[2] / length)


def f32(x):
    """The float32 nearest to x, as a Python float (what the buffer really holds)."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def newell_normal(points):
    """Unnormalised normal of a polygon by Newell's method (exact for planar polygons, the
    least-squares plane for slightly bent ones); points are in counter-clockwise order."""
    n = [0.0, 0.0, 0.0]
    for k in range(len(points)):
        p, q = points[k], points[(k + 1) % len(points)]
        n[0] += (p[1] - q[1]) * (p[2] + q[2])
        n[1] += (p[2] - q[2]) * (p[0] + q[0])
        n[2] += (p[0] - q[0]) * (p[1] + q[1])
    return tuple(n)


# --------------------------------------------------------------------------------------------
# Geometry: one indexed triangle list with per-vertex normals (one glTF primitive)


class Geometry:
    def __init__(self):
        self.positions = []  # (x, y, z) doubles; stored as float32
        self.normals = []    # unit (x, y, z)
        self.indices = []    # flat list, 3 per triangle, counter-clockwise from the front

    @property
    def tri_count(self):
        return len(self.indices) // 3

    def vertex(self, p, n):
        self.positions.append(tuple(float(c) for c in p))
        self.normals.append(tuple(float(c) for c in n))
        return len(self.positions) - 1

    def triangle_flat(self, a, b, c):
        """One triangle with its own three vertices and its face normal (a, b, c counter-clockwise
        from the front)."""
        n = v_normalize(v_cross(v_sub(b, a), v_sub(c, a)))
        self.indices += [self.vertex(a, n), self.vertex(b, n), self.vertex(c, n)]

    def quad(self, pts, toward):
        """A quadrilateral p0..p3 (given in order around its boundary, either orientation) facing
        `toward` (any vector on the front side's half-space). Planar quads share 4 vertices with the
        quad's normal; a bent quad (the Cornell box's red wall is one: its published corners are off
        a plane by ~1 mm) is split into two flat-shaded triangles, so that vertex normals always equal
        the geometric normal of the triangle they belong to."""
        pts = [tuple(float(c) for c in p) for p in pts]
        if v_dot(newell_normal(pts), toward) < 0.0:
            pts = [pts[0], pts[3], pts[2], pts[1]]
        n = newell_normal(pts)
        e1, e2, e3 = v_sub(pts[1], pts[0]), v_sub(pts[2], pts[0]), v_sub(pts[3], pts[0])
        bend = v_dot(v_cross(e1, e2), e3)  # 6 x the tetrahedron volume: 0 when planar
        scale = math.sqrt(v_dot(e1, e1)) * math.sqrt(v_dot(e2, e2)) * math.sqrt(v_dot(e3, e3))
        if abs(bend) <= 1e-12 * scale:
            nn = v_normalize(n)
            base = len(self.positions)
            for p in pts:
                self.vertex(p, nn)
            self.indices += [base, base + 1, base + 2, base, base + 2, base + 3]
        else:
            self.triangle_flat(pts[0], pts[1], pts[2])
            self.triangle_flat(pts[0], pts[2], pts[3])

    def box(self, lo, hi):
        """A closed axis-aligned box, 6 faces x 2 triangles, normals outward."""
        x0, y0, z0 = lo
        x1, y1, z1 = hi
        assert x0 < x1 and y0 < y1 and z0 < z1
        self.quad([(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (1, 0, 0))
        self.quad([(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)], (-1, 0, 0))
        self.quad([(x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0)], (0, 1, 0))
        self.quad([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0, -1, 0))
        self.quad([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, 1))
        self.quad([(x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0)], (0, 0, -1))


# --------------------------------------------------------------------------------------------
# Cameras and lights: glTF nodes look down their local -Z with +Y up (glTF 2.0 Sec. 3.10.1,
# KHR_lights_punctual "direction"), so both are placed by a rotation taking -Z to `forward`.


def quat_look(forward, up=(0.0, 1.0, 0.0)):
    """Unit quaternion (x, y, z, w) rotating local -Z onto `forward` and local +Y towards `up`."""
    f = v_normalize(forward)
    r = v_normalize(v_cross(f, up))
    u = v_cross(r, f)
    b = v_scale(f, -1.0)  # local +Z
    # rotation matrix columns: r (local X), u (local Y), b (local Z); Shepperd's method
    m00, m01, m02 = r[0], u[0], b[0]
    m10, m11, m12 = r[1], u[1], b[1]
    m20, m21, m22 = r[2], u[2], b[2]
    trace = m00 + m11 + m22
    if trace > 0.0:
        s = math.sqrt(trace + 1.0) * 2.0
        q = ((m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s, 0.25 * s)
    elif m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2.0
        q = (0.25 * s, (m01 + m10) / s, (m02 + m20) / s, (m21 - m12) / s)
    elif m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2.0
        q = ((m01 + m10) / s, 0.25 * s, (m12 + m21) / s, (m02 - m20) / s)
    else:
        s = math.sqrt(1.0 + m22 - m00 - m11) * 2.0
        q = ((m02 + m20) / s, (m12 + m21) / s, 0.25 * s, (m10 - m01) / s)
    # +0.0 for exact zeros keeps "-0.0" out of the files
    return [c + 0.0 for c in q]


# --------------------------------------------------------------------------------------------
# glTF document assembly


def to_json(value, indent=""):
    """json.dumps with objects one member per line but arrays of numbers kept on one line, so a
    diff of two generations reads like a diff of the scene."""
    inner = indent + "  "
    if isinstance(value, dict):
        if not value:
            return "{}"
        items = ["%s%s: %s" % (inner, json.dumps(k), to_json(v, inner)) for k, v in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + indent + "}"
    if isinstance(value, list):
        if all(not isinstance(v, (dict, list)) for v in value):
            return "[" + ", ".join(json.dumps(v) for v in value) + "]"
        return "[\n" + ",\n".join(inner + to_json(v, inner) for v in value) + "\n" + indent + "]"
    return json.dumps(value, ensure_ascii=True)


class Scene:
    def __init__(self, name):
        self.name = name
        self.materials = []
        self.meshes = []  # (name, material index, Geometry)
        self.nodes = []
        self.cameras = []
        self.lights = []

    @property
    def tri_count(self):
        return sum(g.tri_count for _, _, g in self.meshes)

    def material(self, name, albedo, emission=None):
        m = {
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [albedo[0], albedo[1], albedo[2], 1.0],
                "metallicFactor": 0.0,
                "roughnessFactor": 1.0,
            },
        }
        if emission is not None:
            m["emissiveFactor"] = list(emission)
        self.materials.append(m)
        return len(self.materials) - 1

    def mesh(self, name, material, geo):
        assert geo.tri_count > 0 and len(geo.positions) <= 65535
        self.meshes.append((name, material, geo))
        self.nodes.append({"name": name, "mesh": len(self.meshes) - 1})

    def camera(self, name, eye, forward, yfov, znear, zfar=None, aspect=None):
        persp = {}
        if aspect is not None:
            persp["aspectRatio"] = aspect
        persp["yfov"] = yfov
        if zfar is not None:
            persp["zfar"] = zfar
        persp["znear"] = znear
        self.cameras.append({"name": name, "type": "perspective", "perspective": persp})
        node = {"name": name, "camera": len(self.cameras) - 1}
        rotation = quat_look(forward)
        if rotation != [0.0, 0.0, 0.0, 1.0]:
            node["rotation"] = rotation
        if tuple(eye) != (0.0, 0.0, 0.0):
            node["translation"] = [float(c) for c in eye]
        self.nodes.append(node)

    def light(self, name, kind, intensity, position=None, direction=None, color=(1.0, 1.0, 1.0)):
        self.lights.append({"name": name, "type": kind, "color": list(color), "intensity": intensity})
        node = {"name": name, "extensions": {"KHR_lights_punctual": {"light": len(self.lights) - 1}}}
        if direction is not None:
            node["rotation"] = quat_look(direction)
        if position is not None and tuple(position) != (0.0, 0.0, 0.0):
            node["translation"] = [float(c) for c in position]
        self.nodes.append(node)

    def document(self):
        """The glTF JSON object with one buffer: all POSITIONs, then all NORMALs, then all indices
        (uint16), so every accessor is naturally aligned."""
        pos_blob, nrm_blob, idx_blob = bytearray(), bytearray(), bytearray()
        accessors, meshes = [], []
        for name, material, geo in self.meshes:
            pos32 = [tuple(f32(c) for c in p) for p in geo.positions]
            acc_pos = len(accessors)
            accessors.append({
                "bufferView": 0, "byteOffset": len(pos_blob), "componentType": 5126,
                "count": len(pos32), "type": "VEC3",
                "min": [min(p[k] for p in pos32) for k in range(3)],
                "max": [max(p[k] for p in pos32) for k in range(3)],
            })
            for p in geo.positions:
                pos_blob += struct.pack("<3f", *p)
            acc_nrm = len(accessors)
            accessors.append({"bufferView": 1, "byteOffset": len(nrm_blob), "componentType": 5126,
                              "count": len(geo.normals), "type": "VEC3"})
            for n in geo.normals:
                nrm_blob += struct.pack("<3f", *n)
            acc_idx = len(accessors)
            accessors.append({"bufferView": 2, "byteOffset": len(idx_blob), "componentType": 5123,
                              "count": len(geo.indices), "type": "SCALAR"})
            idx_blob += struct.pack("<%dH" % len(geo.indices), *geo.indices)
            meshes.append({"name": name, "primitives": [{
                "attributes": {"NORMAL": acc_nrm, "POSITION": acc_pos},
                "indices": acc_idx, "material": material, "mode": 4}]})
        blob = bytes(pos_blob + nrm_blob + idx_blob)
        views = [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(pos_blob), "byteStride": 12, "target": 34962},
            {"buffer": 0, "byteOffset": len(pos_blob), "byteLength": len(nrm_blob), "byteStride": 12,
             "target": 34962},
            {"buffer": 0, "byteOffset": len(pos_blob) + len(nrm_blob), "byteLength": len(idx_blob),
             "target": 34963},
        ]
        uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode("ascii")
        return {
            "asset": {"version": "2.0", "generator": GENERATOR},
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {"KHR_lights_punctual": {"lights": self.lights}},
            "scene": 0,
            "scenes": [{"name": self.name, "nodes": list(range(len(self.nodes)))}],
            "nodes": self.nodes,
            "cameras": self.cameras,
            "meshes": meshes,
            "materials": self.materials,
            "accessors": accessors,
            "bufferViews": views,
            "buffers": [{"byteLength": len(blob), "uri": uri}],
        }

    def write(self, path):
        os.makedirs(os.path.dirname(path), exist_ok=True)
        text = to_json(self.document()) + "\n"
        with open(path, "w", encoding="ascii", newline="\n") as f:
            f.write(text)


# --------------------------------------------------------------------------------------------
# Cornell box: Cornell University Program of Computer Graphics, "Cornell Box Data",
# http://www.graphics.cornell.edu/online/box/data.html (geometry in mm, camera, reflectance
# spectra 400..700 nm in 4 nm steps). The vertex lists below are the published ones, in the
# published order; the frame is kept (right-handed, +Y up, camera looking along +Z), only scaled
# by 0.001 to metres. The light patch (213..343 x 227..332 at y = 548.8) is NOT geometry here:
# softgi lights the box with one point light at the patch centre instead.

CORNELL_ROOM = {
    # name: (material, published vertices in mm)
    "floor": ("white", [(552.8, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 559.2), (549.6, 0.0, 559.2)]),
    "ceiling": ("white", [(556.0, 548.8, 0.0), (556.0, 548.8, 559.2), (0.0, 548.8, 559.2),
                          (0.0, 548.8, 0.0)]),
    "back_wall": ("white", [(549.6, 0.0, 559.2), (0.0, 0.0, 559.2), (0.0, 548.8, 559.2),
                            (556.0, 548.8, 559.2)]),
    "right_wall": ("green", [(0.0, 0.0, 559.2), (0.0, 0.0, 0.0), (0.0, 548.8, 0.0), (0.0, 548.8, 559.2)]),
    "left_wall": ("red", [(552.8, 0.0, 0.0), (549.6, 0.0, 559.2), (556.0, 548.8, 559.2),
                          (556.0, 548.8, 0.0)]),
}
CORNELL_SHORT_BLOCK = [
    [(130.0, 165.0, 65.0), (82.0, 165.0, 225.0), (240.0, 165.0, 272.0), (290.0, 165.0, 114.0)],
    [(290.0, 0.0, 114.0), (290.0, 165.0, 114.0), (240.0, 165.0, 272.0), (240.0, 0.0, 272.0)],
    [(130.0, 0.0, 65.0), (130.0, 165.0, 65.0), (290.0, 165.0, 114.0), (290.0, 0.0, 114.0)],
    [(82.0, 0.0, 225.0), (82.0, 165.0, 225.0), (130.0, 165.0, 65.0), (130.0, 0.0, 65.0)],
    [(240.0, 0.0, 272.0), (240.0, 165.0, 272.0), (82.0, 165.0, 225.0), (82.0, 0.0, 225.0)],
]
CORNELL_TALL_BLOCK = [
    [(423.0, 330.0, 247.0), (265.0, 330.0, 296.0), (314.0, 330.0, 456.0), (472.0, 330.0, 406.0)],
    [(423.0, 0.0, 247.0), (423.0, 330.0, 247.0), (472.0, 330.0, 406.0), (472.0, 0.0, 406.0)],
    [(472.0, 0.0, 406.0), (472.0, 330.0, 406.0), (314.0, 330.0, 456.0), (314.0, 0.0, 456.0)],
    [(314.0, 0.0, 456.0), (314.0, 330.0, 456.0), (265.0, 330.0, 296.0), (265.0, 0.0, 296.0)],
    [(265.0, 0.0, 296.0), (265.0, 330.0, 296.0), (423.0, 330.0, 247.0), (423.0, 0.0, 247.0)],
]
CORNELL_LIGHT_PATCH = [(343.0, 548.8, 227.0), (343.0, 548.8, 332.0), (213.0, 548.8, 332.0),
                       (213.0, 548.8, 227.0)]
CORNELL_CAMERA = {"position": (278.0, 273.0, -800.0), "direction": (0.0, 0.0, 1.0),
                  "focal_length": 0.035, "film": 0.025}

# Measured diffuse reflectance spectra, 400..700 nm every 4 nm (76 samples), same source.
SPECTRUM_WHITE = [
    0.343, 0.445, 0.551, 0.624, 0.665, 0.687, 0.708, 0.723, 0.715, 0.710, 0.745, 0.758, 0.739, 0.767,
    0.777, 0.765, 0.751, 0.745, 0.748, 0.729, 0.745, 0.757, 0.753, 0.750, 0.746, 0.747, 0.735, 0.732,
    0.739, 0.734, 0.725, 0.721, 0.733, 0.725, 0.732, 0.743, 0.744, 0.748, 0.728, 0.716, 0.733, 0.726,
    0.713, 0.740, 0.754, 0.764, 0.752, 0.736, 0.734, 0.741, 0.740, 0.732, 0.745, 0.755, 0.751, 0.744,
    0.731, 0.733, 0.744, 0.731, 0.712, 0.708, 0.729, 0.730, 0.727, 0.707, 0.703, 0.729, 0.750, 0.760,
    0.751, 0.739, 0.724, 0.730, 0.740, 0.737]
SPECTRUM_GREEN = [
    0.092, 0.096, 0.098, 0.097, 0.098, 0.095, 0.095, 0.097, 0.095, 0.094, 0.097, 0.098, 0.096, 0.101,
    0.103, 0.104, 0.107, 0.109, 0.112, 0.115, 0.125, 0.140, 0.160, 0.187, 0.229, 0.285, 0.343, 0.390,
    0.435, 0.464, 0.472, 0.476, 0.481, 0.462, 0.447, 0.441, 0.426, 0.406, 0.373, 0.347, 0.337, 0.314,
    0.285, 0.277, 0.266, 0.250, 0.230, 0.207, 0.186, 0.171, 0.160, 0.148, 0.141, 0.136, 0.130, 0.126,
    0.123, 0.121, 0.122, 0.119, 0.114, 0.115, 0.117, 0.117, 0.118, 0.120, 0.122, 0.128, 0.132, 0.139,
    0.144, 0.146, 0.150, 0.152, 0.157, 0.159]
SPECTRUM_RED = [
    0.040, 0.046, 0.048, 0.053, 0.049, 0.050, 0.053, 0.055, 0.057, 0.056, 0.059, 0.057, 0.061, 0.061,
    0.060, 0.062, 0.062, 0.062, 0.061, 0.062, 0.060, 0.059, 0.057, 0.058, 0.058, 0.058, 0.056, 0.055,
    0.056, 0.059, 0.057, 0.055, 0.059, 0.059, 0.058, 0.059, 0.061, 0.061, 0.063, 0.063, 0.067, 0.068,
    0.072, 0.080, 0.090, 0.099, 0.124, 0.154, 0.192, 0.255, 0.287, 0.349, 0.402, 0.443, 0.487, 0.513,
    0.558, 0.584, 0.620, 0.606, 0.609, 0.651, 0.612, 0.610, 0.650, 0.638, 0.627, 0.620, 0.630, 0.628,
    0.642, 0.639, 0.657, 0.639, 0.635, 0.642]


def cie_xyz(lam):
    """CIE 1931 2-degree colour matching functions, multi-lobe Gaussian fit of Wyman, Sloan and
    Shirley, "Simple Analytic Approximations to the CIE XYZ Color Matching Functions", JCGT 2(2),
    2013, the multi-lobe piecewise-Gaussian fit (close to the tabulated functions; the albedos it
    yields are good to about the second decimal, far finer than any RGB stand-in for a spectrum)."""
    def g(x, mu, s1, s2):
        t = (x - mu) / (s1 if x < mu else s2)
        return math.exp(-0.5 * t * t)
    x = (1.056 * g(lam, 599.8, 37.9, 31.0) + 0.362 * g(lam, 442.0, 16.0, 26.7)
         - 0.065 * g(lam, 501.1, 20.4, 26.2))
    y = 0.821 * g(lam, 568.8, 46.9, 40.5) + 0.286 * g(lam, 530.9, 16.3, 31.1)
    z = 1.217 * g(lam, 437.0, 11.8, 36.0) + 0.681 * g(lam, 459.0, 26.0, 13.8)
    return x, y, z


def spectrum_to_albedo(samples):
    """Linear-sRGB albedo of a reflectance spectrum lit by white (equal-energy) light: integrate
    against the CMFs (trapezoid rule over the 400..700 nm samples), convert XYZ to linear sRGB
    (IEC 61966-2-1 matrix) and divide per channel by the result for a perfect reflector, so a flat
    spectrum rho gives exactly (rho, rho, rho). Rounded to 3 decimals (the measurements have 3)."""
    xyz_to_rgb = ((3.2404542, -1.5371385, -0.4985314),
                  (-0.9692660, 1.8760108, 0.0415560),
                  (0.0556434, -0.2040259, 1.0572252))

    def rgb(spec):
        acc = [0.0, 0.0, 0.0]
        for k, s in enumerate(spec):
            w = 0.5 if k in (0, len(spec) - 1) else 1.0
            cmf = cie_xyz(400.0 + 4.0 * k)
            for c in range(3):
                acc[c] += w * s * cmf[c]
        return [sum(xyz_to_rgb[r][c] * acc[c] for c in range(3)) for r in range(3)]

    assert len(samples) == 76
    ref, val = rgb([1.0] * 76), rgb(samples)
    return tuple(round(max(val[c] / ref[c], 0.0), 3) for c in range(3))


def mm(p):
    return (p[0] * 0.001, p[1] * 0.001, p[2] * 0.001)


def centroid(points):
    n = float(len(points))
    return (sum(p[0] for p in points) / n, sum(p[1] for p in points) / n, sum(p[2] for p in points) / n)


CORNELL_LIGHT_INTENSITY = 1.0  # W/sr; see scenes/cornell-box/README.md


def make_cornell_box():
    s = Scene("cornell-box")
    mats = {
        "white": s.material("white", spectrum_to_albedo(SPECTRUM_WHITE)),
        "red": s.material("red", spectrum_to_albedo(SPECTRUM_RED)),
        "green": s.material("green", spectrum_to_albedo(SPECTRUM_GREEN)),
    }
    # Room surfaces face the inside of the box: the middle of the published volume.
    room_centre = (0.278, 0.2744, 0.2796)
    for name, (mat, quad) in CORNELL_ROOM.items():
        g = Geometry()
        pts = [mm(p) for p in quad]
        g.quad(pts, v_sub(room_centre, centroid(pts)))
        s.mesh(name, mats[mat], g)
    # Blocks: 5 published faces each (no bottom: they stand on the floor), facing outward.
    for name, faces in (("short_block", CORNELL_SHORT_BLOCK), ("tall_block", CORNELL_TALL_BLOCK)):
        g = Geometry()
        top = [mm(p) for p in faces[0]]
        mid = centroid(top)
        mid = (mid[0], top[0][1] * 0.5, mid[2])
        for quad in faces:
            pts = [mm(p) for p in quad]
            g.quad(pts, v_sub(centroid(pts), mid))
        s.mesh(name, mats["white"], g)
    cam = CORNELL_CAMERA
    # vertical fov of a 35 mm lens on 25 mm film: 2 atan(12.5 / 35) = 39.3077 deg
    yfov = round(2.0 * math.atan(0.5 * cam["film"] / cam["focal_length"]), 12)
    s.camera("camera", mm(cam["position"]), cam["direction"], yfov, znear=0.01, aspect=1.0)
    c = centroid([mm(p) for p in CORNELL_LIGHT_PATCH])
    s.light("ceiling_light", "point", CORNELL_LIGHT_INTENSITY, position=(c[0], c[1] - 0.01, c[2]))
    return s


# --------------------------------------------------------------------------------------------
# Closed sphere: icosahedron, 3 rounds of 4:1 midpoint subdivision (20 * 4^3 = 1280 triangles,
# 642 vertices), every vertex projected onto the unit sphere. Midpoints are cached per undirected
# edge, so neighbouring triangles share the very same vertex index: the mesh is closed by
# construction. Triangles are wound so that the INSIDE is the front; normals = -position.

SPHERE_LEVELS = 3


def make_closed_sphere():
    t = (1.0 + math.sqrt(5.0)) / 2.0
    verts = [v_normalize(p) for p in [
        (-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
        (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(SPHERE_LEVELS):
        cache, out = {}, []

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                verts.append(v_normalize(v_scale(v_add(verts[a], verts[b]), 0.5)))
                cache[key] = len(verts) - 1
            return cache[key]

        for a, b, c in faces:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            out += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = out
    g = Geometry()
    for p in verts:
        g.vertex(p, v_scale(p, -1.0))
    for a, b, c in faces:
        n = v_cross(v_sub(verts[b], verts[a]), v_sub(verts[c], verts[a]))
        if v_dot(n, verts[a]) > 0.0:  # outward-wound: flip so the inside is the front
            b, c = c, b
        g.indices += [a, b, c]
    s = Scene("closed-sphere")
    m = s.material("white_emissive", (0.5, 0.5, 0.5), emission=(1.0, 1.0, 1.0))
    s.mesh("sphere", m, g)
    s.camera("camera", (0.0, 0.0, 0.0), (0.0, 0.0, -1.0), round(math.radians(90.0), 12), znear=0.01)
    s.light("centre_light", "point", 1.0, position=(0.0, 0.0, 0.0))
    return s


# --------------------------------------------------------------------------------------------
# Box room with a window: x in [-2, 2], y in [0, 3], z in [-2, 2]; window in the z = -2 wall,
# x in [-0.75, 0.75], y in [1.0, 2.2]. Every face is gridded by the same coordinate lines
# (x: -2, -0.75, 0.75, 2; y: 0, 1, 2.2, 3) so that edges meet edge to edge (no T-junctions): the
# mesh is closed except for the window's rim. All walls face inward.

ROOM_X = (-2.0, -0.75, 0.75, 2.0)
ROOM_Y = (0.0, 1.0, 2.2, 3.0)
ROOM_Z = (-2.0, 2.0)
WINDOW = {"x": (-0.75, 0.75), "y": (1.0, 2.2), "z": -2.0}
SUN_DIRECTION = (1.0, -2.0, 3.0)  # travel direction, normalised at use: elevation 32.3 deg
SUN_IRRADIANCE = 3.0              # W/m^2 on a surface facing the sun


def make_box_room_hole():
    s = Scene("box-room-hole")
    wall = s.material("wall", (0.8, 0.8, 0.8))
    floor = s.material("floor", (0.6, 0.6, 0.6))

    def grid(g, us, vs, to_xyz, inward, skip=None):
        for i in range(len(us) - 1):
            for j in range(len(vs) - 1):
                if skip is not None and skip(i, j):
                    continue
                a, b = us[i], us[i + 1]
                c, d = vs[j], vs[j + 1]
                g.quad([to_xyz(a, c), to_xyz(b, c), to_xyz(b, d), to_xyz(a, d)], inward)

    g = Geometry()
    grid(g, ROOM_X, ROOM_Z, lambda x, z: (x, 0.0, z), (0, 1, 0))
    s.mesh("floor", floor, g)
    g = Geometry()
    grid(g, ROOM_X, ROOM_Z, lambda x, z: (x, 3.0, z), (0, -1, 0))
    s.mesh("ceiling", wall, g)
    g = Geometry()
    # the window is the middle cell of the 3 x 3 grid of the z = -2 wall
    grid(g, ROOM_X, ROOM_Y, lambda x, y: (x, y, -2.0), (0, 0, 1), skip=lambda i, j: i == 1 and j == 1)
    grid(g, ROOM_X, ROOM_Y, lambda x, y: (x, y, 2.0), (0, 0, -1))
    grid(g, ROOM_Y, ROOM_Z, lambda y, z: (-2.0, y, z), (1, 0, 0))
    grid(g, ROOM_Y, ROOM_Z, lambda y, z: (2.0, y, z), (-1, 0, 0))
    s.mesh("walls", wall, g)

    # The sunlit patch is the window swept along the sun direction down to the floor: the window
    # centre (0, 1.6, -2) lands at (0.8, 0, 0.4). The camera stands in the opposite corner.
    sun = v_normalize(SUN_DIRECTION)
    s.camera("camera", (-1.5, 1.6, 1.7), v_sub((0.8, 0.0, 0.4), (-1.5, 1.6, 1.7)),
             round(math.radians(60.0), 12), znear=0.01, zfar=20.0)
    s.light("sun", "directional", SUN_IRRADIANCE, direction=sun)
    return s


# --------------------------------------------------------------------------------------------
# Maze: 8 x 8 cells of 1 m on x, z in [-4, 4], carved by an iterative depth-first search
# ("recursive backtracker") driven by xorshift32 from a fixed seed, with an entrance at the
# z = -4 side of cell (0, 0) and an exit at the z = +4 side of cell (7, 7). Walls are 0.1 m thick,
# 1.5 m high closed boxes (bottom face included) with outward normals. Boxes never overlap:
# runs along x are merged into one box that also covers the wall crossings; runs along z stop
# flush against them. The floor is one 10 x 10 m quad.

MAZE_N = 8
MAZE_CELL = 1.0
MAZE_ORIGIN = -4.0
MAZE_WALL_T = 0.1
MAZE_WALL_H = 1.5
MAZE_SEED = 0x50F761  # "softgi"
MAZE_LIGHT = (0.5, 4.0, 0.5)
MAZE_LIGHT_INTENSITY = 40.0  # W/sr


def xorshift32(state):
    state ^= (state << 13) & 0xFFFFFFFF
    state ^= state >> 17
    state ^= (state << 5) & 0xFFFFFFFF
    return state & 0xFFFFFFFF


def carve_maze(n, seed):
    """Returns (h, v): h[j][i] is the wall on line z = j between nodes i and i+1 (j in 0..n,
    i in 0..n-1); v[i][j] is the wall on line x = i between nodes j and j+1."""
    h = [[True] * n for _ in range(n + 1)]
    v = [[True] * n for _ in range(n + 1)]
    seen = [[False] * n for _ in range(n)]
    state = seed
    stack = [(0, 0)]
    seen[0][0] = True
    while stack:
        i, j = stack[-1]
        options = [(di, dj) for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1))
                   if 0 <= i + di < n and 0 <= j + dj < n and not seen[i + di][j + dj]]
        if not options:
            stack.pop()
            continue
        state = xorshift32(state)
        di, dj = options[state % len(options)]
        if di == 1:
            v[i + 1][j] = False
        elif di == -1:
            v[i][j] = False
        elif dj == 1:
            h[j + 1][i] = False
        else:
            h[j][i] = False
        seen[i + di][j + dj] = True
        stack.append((i + di, j + dj))
    h[0][0] = False          # entrance
    h[n][n - 1] = False      # exit
    return h, v


def maze_boxes():
    n, c, o, t, hgt = MAZE_N, MAZE_CELL, MAZE_ORIGIN, MAZE_WALL_T, MAZE_WALL_H
    h, v = carve_maze(n, MAZE_SEED)
    boxes = []
    # runs along x, covering the crossings at their nodes
    for j in range(n + 1):
        i = 0
        while i < n:
            if not h[j][i]:
                i += 1
                continue
            i0 = i
            while i < n and h[j][i]:
                i += 1
            boxes.append(((o + i0 * c - t / 2, 0.0, o + j * c - t / 2),
                          (o + i * c + t / 2, hgt, o + j * c + t / 2)))

    def covered(i, j):  # is node (i, j) inside a box along x?
        return (i > 0 and h[j][i - 1]) or (i < n and h[j][i])

    # runs along z, split at and stopped flush against covered nodes
    for i in range(n + 1):
        j = 0
        while j < n:
            if not v[i][j]:
                j += 1
                continue
            j0 = j
            j += 1
            while j < n and v[i][j] and not covered(i, j):
                j += 1
            z0 = o + j0 * c + (t / 2 if covered(i, j0) else -t / 2)
            z1 = o + j * c + (-t / 2 if covered(i, j) else t / 2)
            boxes.append(((o + i * c - t / 2, 0.0, z0), (o + i * c + t / 2, hgt, z1)))
    return boxes


def make_maze():
    s = Scene("maze")
    floor = s.material("floor", (0.6, 0.6, 0.6))
    wall = s.material("wall", (0.75, 0.75, 0.75))
    g = Geometry()
    g.quad([(-5.0, 0.0, -5.0), (5.0, 0.0, -5.0), (5.0, 0.0, 5.0), (-5.0, 0.0, 5.0)], (0, 1, 0))
    s.mesh("floor", floor, g)
    g = Geometry()
    for lo, hi in maze_boxes():
        g.box(lo, hi)
    s.mesh("walls", wall, g)
    eye = (0.0, 9.0, 8.0)
    s.camera("camera", eye, v_sub((0.0, 0.0, 0.5), eye), round(math.radians(50.0), 12), znear=0.05, zfar=50.0)
    s.light("lamp", "point", MAZE_LIGHT_INTENSITY, position=MAZE_LIGHT)
    return s


# --------------------------------------------------------------------------------------------
# Corridor: two rooms joined by a Z-shaped corridor on a grid of 1 m cells (x right, z towards
# the camera's left), 2.5 m high, for SMC Instant Radiosity's indirect visibility (Hedman 2017
# Sec. 3.2.2 and Fig. 5). The free space is a union of cell rectangles; every face of a free cell
# that borders solid space is one inward-facing quad, so the interior is closed.
#   room A (camera)  x 0..4,   z 0..4
#   leg 1            x 4..8,   z 1..2   (leaves room A eastwards)
#   leg 2            x 7..8,   z 2..7   (turns south)
#   leg 3            x 8..11,  z 6..7   (turns east again)
#   room B (light)   x 11..15, z 4..9
# The camera looks down leg 1. Any segment from a point of leg 1 or room A into leg 3 must pass
# through leg 2 (x 7..8 for z 2..6), so it reaches at most x = 8.25 in leg 3: room B and leg 3
# beyond x = 8.25 are hidden from every directly visible point (second-order hidden). The light
# hangs in room B, where it shines down leg 3; room A gets light only around two corners.

CORRIDOR_H = 2.5
CORRIDOR_RECTS = [(0, 4, 0, 4), (4, 8, 1, 2), (7, 8, 2, 7), (8, 11, 6, 7), (11, 15, 4, 9)]
CORRIDOR_LIGHT = (12.5, 2.0, 6.5)
CORRIDOR_LIGHT_INTENSITY = 200.0  # W/sr


def make_corridor():
    s = Scene("corridor")
    wall = s.material("wall", (0.75, 0.75, 0.75))
    floor = s.material("floor", (0.6, 0.6, 0.6))
    free = set()
    for x0, x1, z0, z1 in CORRIDOR_RECTS:
        for x in range(x0, x1):
            for z in range(z0, z1):
                free.add((x, z))
    h = CORRIDOR_H
    gf, gw = Geometry(), Geometry()
    for x, z in sorted(free):
        gf.quad([(x, 0.0, z), (x + 1, 0.0, z), (x + 1, 0.0, z + 1), (x, 0.0, z + 1)], (0, 1, 0))
        gw.quad([(x, h, z), (x + 1, h, z), (x + 1, h, z + 1), (x, h, z + 1)], (0, -1, 0))
        if (x + 1, z) not in free:
            gw.quad([(x + 1, 0.0, z), (x + 1, h, z), (x + 1, h, z + 1), (x + 1, 0.0, z + 1)], (-1, 0, 0))
        if (x - 1, z) not in free:
            gw.quad([(x, 0.0, z), (x, h, z), (x, h, z + 1), (x, 0.0, z + 1)], (1, 0, 0))
        if (x, z + 1) not in free:
            gw.quad([(x, 0.0, z + 1), (x + 1, 0.0, z + 1), (x + 1, h, z + 1), (x, h, z + 1)], (0, 0, -1))
        if (x, z - 1) not in free:
            gw.quad([(x, 0.0, z), (x + 1, 0.0, z), (x + 1, h, z), (x, h, z)], (0, 0, 1))
    s.mesh("floor", floor, gf)
    s.mesh("walls", wall, gw)
    eye = (0.5, 1.5, 1.6)
    s.camera("camera", eye, v_sub((8.0, 1.2, 1.5), eye), round(math.radians(60.0), 12), znear=0.05, zfar=50.0)
    s.light("lamp", "point", CORRIDOR_LIGHT_INTENSITY, position=CORRIDOR_LIGHT)
    return s


# --------------------------------------------------------------------------------------------

SCENES = [
    ("scenes/cornell-box/cornell-box.gltf", make_cornell_box),
    ("scenes/closed-sphere/closed-sphere.gltf", make_closed_sphere),
    ("scenes/box-room-hole/box-room-hole.gltf", make_box_room_hole),
    ("scenes/maze/maze.gltf", make_maze),
    ("scenes/corridor/corridor.gltf", make_corridor),
]


def main(argv):
    root = argv[1] if len(argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    for rel, make in SCENES:
        scene = make()
        scene.write(os.path.join(root, rel))
        verts = sum(len(g.positions) for _, _, g in scene.meshes)
        print("%-42s %6d triangles %6d vertices" % (rel, scene.tri_count, verts))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
