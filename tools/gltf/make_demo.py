#!/usr/bin/env python3
"""Writes scenes/gltf_demo.gltf: a small glTF 2.0 scene with every kind of thing the loader
reads (nodes with TRS, a checker texture with a sampler and KHR_texture_transform, metallic and
dielectric principled materials, an emissive panel with KHR_materials_emissive_strength, a
KHR_lights_punctual spot light, a perspective camera). Deterministic: rerun to regenerate.

Usage: python3 tools/gltf/make_demo.py [OUT]"""
import base64, json, math, struct, sys, zlib
from pathlib import Path

bin_data = bytearray()
views, accessors = [], []


def view(data):
    while len(bin_data) % 4:
        bin_data.append(0)
    views.append({"buffer": 0, "byteOffset": len(bin_data), "byteLength": len(data)})
    bin_data.extend(data)
    return len(views) - 1


def floats(values, ty):
    n = {"VEC2": 2, "VEC3": 3}[ty]
    a = {"bufferView": view(struct.pack(f"<{len(values)}f", *values)), "componentType": 5126,
         "count": len(values) // n, "type": ty}
    if ty == "VEC3":
        a["min"] = [min(values[k::3]) for k in range(3)]
        a["max"] = [max(values[k::3]) for k in range(3)]
    accessors.append(a)
    return len(accessors) - 1


def indices(values):
    accessors.append({"bufferView": view(struct.pack(f"<{len(values)}H", *values)), "componentType": 5123,
                      "count": len(values), "type": "SCALAR"})
    return len(accessors) - 1


def png(w, h, rows):
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


# A quad in the xz plane facing +y, and a unit cube, with uvs.
quad_p = floats([-1, 0, 1, 1, 0, 1, 1, 0, -1, -1, 0, -1], "VEC3")
quad_uv = floats([0, 1, 1, 1, 1, 0, 0, 0], "VEC2")
quad_n = floats([0, 1, 0] * 4, "VEC3")
quad_i = indices([0, 1, 2, 0, 2, 3])
cube_p, cube_n, cube_uv, cube_i = [], [], [], []
for axis in range(3):
    for sign in (1, -1):
        n = [0, 0, 0]
        n[axis] = sign
        u = [0, 0, 0]
        u[(axis + 1) % 3] = 1
        v = [0, 0, 0]
        v[(axis + 2) % 3] = 1
        if sign < 0:
            u, v = v, u
        base = len(cube_p) // 3
        for (a, b) in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            cube_p += [0.5 * (n[k] + a * u[k] + b * v[k]) for k in range(3)]
            cube_n += n
            cube_uv += [(a + 1) / 2, (1 - b) / 2]
        cube_i += [base, base + 1, base + 2, base, base + 2, base + 3]
cp, cn, cu, ci = floats(cube_p, "VEC3"), floats(cube_n, "VEC3"), floats(cube_uv, "VEC2"), indices(cube_i)

checker = png(8, 8, [[c for x in range(8) for c in ((230, 230, 230) if (x // 4 + y // 4) % 2 == 0 else (40, 40, 40))]
                     for y in range(8)])
image_view = view(checker)


def look_at(eye, target):
    """The rotation (a quaternion x, y, z, w) that turns a node's -z toward target from eye, +y up."""
    sub = lambda a, b: [a[i] - b[i] for i in range(3)]
    cross = lambda a, b: [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    norm = lambda a: [c / math.sqrt(sum(x * x for x in a)) for c in a]
    z = norm(sub(eye, target))
    x = norm(cross([0, 1, 0], z))
    y = cross(z, x)
    m = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
    w = math.sqrt(max(0.0, 1 + m[0][0] + m[1][1] + m[2][2])) / 2
    q = [(m[2][1] - m[1][2]) / (4 * w), (m[0][2] - m[2][0]) / (4 * w), (m[1][0] - m[0][1]) / (4 * w), w]
    return [round(c, 7) for c in q]


def yaw(deg):
    h = math.radians(deg) / 2
    return [0.0, round(math.sin(h), 6), 0.0, round(math.cos(h), 6)]


doc = {
    "asset": {"version": "2.0", "generator": "neumann tools/gltf/make_demo.py"},
    "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_texture_transform"],
    "scene": 0,
    "scenes": [{"name": "demo", "nodes": [0, 1, 2, 3, 4, 5]}],
    "nodes": [
        {"name": "floor", "mesh": 0, "scale": [3, 1, 3]},
        {"name": "red cube", "mesh": 1, "translation": [-0.7, 0.4, 0], "rotation": yaw(30), "scale": [0.8, 0.8, 0.8]},
        {"name": "gold cube", "mesh": 2, "translation": [0.8, 0.3, 0.5], "rotation": yaw(-20), "scale": [0.6, 0.6, 0.6]},
        {"name": "panel", "mesh": 3, "translation": [0, 2.5, 0], "rotation": [1, 0, 0, 0], "scale": [0.5, 1, 0.5]},
        {"name": "spot", "translation": [2.5, 3, 2.5], "rotation": look_at([2.5, 3, 2.5], [0, 0, 0]),
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "camera", "camera": 0, "translation": [0, 1.4, 4.5], "rotation": look_at([0, 1.4, 4.5], [0, 0.4, 0])},
    ],
    "meshes": [
        {"name": "floor", "primitives": [{"attributes": {"POSITION": quad_p, "NORMAL": quad_n, "TEXCOORD_0": quad_uv},
                                          "indices": quad_i, "material": 0}]},
        {"name": "red cube", "primitives": [{"attributes": {"POSITION": cp, "NORMAL": cn, "TEXCOORD_0": cu},
                                             "indices": ci, "material": 1}]},
        {"name": "gold cube", "primitives": [{"attributes": {"POSITION": cp, "NORMAL": cn, "TEXCOORD_0": cu},
                                              "indices": ci, "material": 2}]},
        {"name": "panel", "primitives": [{"attributes": {"POSITION": quad_p, "NORMAL": quad_n}, "indices": quad_i,
                                          "material": 3}]},
    ],
    "materials": [
        {"name": "checker", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"scale": [3, 3]}}},
            "metallicFactor": 0.0, "roughnessFactor": 0.8}},
        {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.15, 0.1, 1], "metallicFactor": 0.0,
                                                  "roughnessFactor": 0.35}},
        {"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.77, 0.34, 1], "metallicFactor": 1.0,
                                                   "roughnessFactor": 0.25}},
        {"name": "panel", "emissiveFactor": [1, 0.95, 0.85],
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}},
         "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0.0}},
    ],
    "textures": [{"source": 0, "sampler": 0}],
    "samplers": [{"magFilter": 9728, "wrapS": 10497, "wrapT": 10497}],
    "images": [{"bufferView": image_view, "mimeType": "image/png"}],
    "cameras": [{"name": "view", "type": "perspective",
                 "perspective": {"yfov": 0.7, "aspectRatio": 1.5, "znear": 0.05, "zfar": 100}}],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "spot", "type": "spot", "color": [1, 0.9, 0.8], "intensity": 25000,
         "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.45}}]}},
}
doc["buffers"] = [{"byteLength": len(bin_data),
                   "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(bin_data)).decode()}]
doc["bufferViews"] = views
doc["accessors"] = accessors
out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / "scenes" / "gltf_demo.gltf"
out.write_text(json.dumps(doc, indent=1) + "\n")
print(f"wrote {out} ({out.stat().st_size} bytes)")
