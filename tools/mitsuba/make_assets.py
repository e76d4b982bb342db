"""Writes the small procedural assets of neumann's validation scenes (scenes/assets/):
- sky.exr: a 128x64 lat-long HDR sky (Mitsuba's convention: row 0 is up, +y): a blue gradient
  above the horizon, a dark brown ground, and a sun of 10 degrees radius and radiance ~300 (dynamic range ~10^3; a smaller,
  brighter sun makes the caustics of the spheres on the ground fireflies that swamp a
  short-render comparison).
- tiles.png: a 64x64 sRGB texture that is not symmetric (an 'F' of coloured blocks on a grid),
  so a flipped or mirrored lookup shows.
- knot.obj and knot.serialized: a low-polygon torus knot without normals (Mitsuba computes smooth
  vertex normals for such meshes; faceted shading would show), the serialized file (zlib,
  version 4) holding a small triangle first so that shape_index 1 picks the knot.
- bumps_normal.png: a tangent-space normal map of round bumps (raw 8-bit), for normalmap.
- blob.vol: a signed distance field (a sphere and a torus) on a 24^3 grid, for sdfgrid.
- flakes.vol: SGGX matrices (six channels) on a 12^3 grid, fibres below and surface-like flakes
  above, for the sggx phase function.
- tufts.txt and coil.txt: Mitsuba's curve files (x y z radius per line, blank lines between
  curves) of a tuft of bent strands thinning toward their tips and of a coil of constant
  radius, for linearcurve.
Needs numpy and Mitsuba (for its EXR/PNG writer): run with the venv that renders the references."""
import math
import struct
import zlib
import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")

w, h = 128, 64
sky = np.zeros((h, w, 3), dtype=np.float32)
sun_dir = np.array([0.55, 0.6, -0.58])
sun_dir /= np.linalg.norm(sun_dir)
for j in range(h):
    theta = (j + 0.5) / h * math.pi  # from +y
    for i in range(w):
        phi = (i + 0.5) / w * 2 * math.pi
        d = np.array([math.sin(phi) * math.sin(theta), math.cos(theta), -math.cos(phi) * math.sin(theta)])
        up = math.cos(theta)
        if up > 0:
            sky[j, i] = np.array([0.35, 0.55, 1.0]) * (0.4 + 0.6 * up) + np.array([0.9, 0.8, 0.6]) * (1 - up) ** 4 * 0.6
        else:
            sky[j, i] = [0.12, 0.09, 0.06]
        if np.dot(d, sun_dir) > math.cos(math.radians(10.0)):
            sky[j, i] = [330.0, 290.0, 230.0]
mi.Bitmap(sky).write("scenes/assets/sky.exr")

n = 64
tex = np.zeros((n, n, 3), dtype=np.float32)
for y in range(n):
    for x in range(n):
        c = 0.85 if ((x // 8) + (y // 8)) % 2 == 0 else 0.65
        tex[y, x] = [c, c, c * 0.9]
# An 'F': vertical bar on the left, two bars to the right at the top and middle (rows from the top).
tex[8:56, 10:20] = [0.8, 0.1, 0.1]
tex[8:18, 20:52] = [0.1, 0.2, 0.8]
tex[28:36, 20:42] = [0.1, 0.6, 0.15]
img = mi.Bitmap(tex).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True)
img.write("scenes/assets/tiles.png")

# A (2, 3) torus knot tube: 64 segments around the curve, 6 around the tube.
seg, ring, r_tube = 64, 6, 0.18
verts, faces = [], []
def knot(t):
    r = 0.6 + 0.3 * math.cos(3 * t)
    return np.array([r * math.cos(2 * t), 0.3 * math.sin(3 * t), r * math.sin(2 * t)])
for i in range(seg):
    t = 2 * math.pi * i / seg
    p, q = knot(t), knot(t + 1e-3)
    tangent = (q - p) / np.linalg.norm(q - p)
    side = np.cross(tangent, [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)
    up = np.cross(side, tangent)
    for j in range(ring):
        a = 2 * math.pi * j / ring
        verts.append(p + r_tube * (math.cos(a) * side + math.sin(a) * up))
for i in range(seg):
    for j in range(ring):
        a, b = i * ring + j, ((i + 1) % seg) * ring + j
        c, d = ((i + 1) % seg) * ring + (j + 1) % ring, i * ring + (j + 1) % ring
        faces += [(a, b, c), (a, c, d)]
with open("scenes/assets/knot.obj", "w") as f:
    f.write("# (2, 3) torus knot, no normals: written by tools/mitsuba/make_assets.py\n")
    for v in verts:
        f.write("v %.5f %.5f %.5f\n" % tuple(v))
    for a, b, c in faces:
        f.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))


def serialized_mesh(vs, fs, name):
    raw = struct.pack("<I", 0x1000) + name + b"\0" + struct.pack("<QQ", len(vs), len(fs))
    raw += b"".join(struct.pack("<fff", *map(float, v)) for v in vs)
    raw += b"".join(struct.pack("<III", *f) for f in fs)
    return struct.pack("<HH", 0x041C, 4) + zlib.compress(raw)


first = serialized_mesh([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 2)], b"triangle")
second = serialized_mesh(verts, faces, b"knot")
with open("scenes/assets/knot.serialized", "wb") as f:
    f.write(first + second + struct.pack("<QQI", 0, len(first), 2))
# The knot as an ASCII PLY with per-vertex colours (a hue around the curve) and per-face colours
# (alternating bands), for Mitsuba's mesh_attribute textures (vertex_color, face_color).
with open("scenes/assets/knot_colors.ply", "w") as f:
    f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n" % len(verts))
    f.write("property float r\nproperty float g\nproperty float b\n")
    f.write("element face %d\nproperty list uchar int vertex_indices\n" % len(faces))
    f.write("property float r\nproperty float g\nproperty float b\nend_header\n")
    for k, v in enumerate(verts):
        h = 2 * math.pi * (k // ring) / seg
        rgb = [0.5 + 0.4 * math.cos(h + o) for o in (0.0, 2.1, 4.2)]
        f.write("%.5f %.5f %.5f %.3f %.3f %.3f\n" % (*v, *rgb))
    for k, (a, b, c) in enumerate(faces):
        band = (k // (2 * ring)) % 2
        f.write("3 %d %d %d %s\n" % (a, b, c, "0.8 0.7 0.2" if band else "0.2 0.3 0.8"))

# An SDF for Mitsuba's sdfgrid: a sphere joined to a torus lying around it, in the unit cube,
# on a 24^3 grid, as a Mitsuba grid volume (.vol: 'VOL' 3, float32 encoding, resolution, 1
# channel, bbox, data with x fastest). Cubic, because Mitsuba 3.9.1 renders nothing of a grid
# whose resolutions differ (a bug of its voxel indexing, fixed later); neumann's unit tests
# cover such grids.
nx, ny, nz = 24, 24, 24
zs, ys, xs = np.meshgrid(np.linspace(0, 1, nz), np.linspace(0, 1, ny), np.linspace(0, 1, nx), indexing="ij")
sphere = np.sqrt((xs - 0.3) ** 2 + (ys - 0.5) ** 2 + (zs - 0.45) ** 2) - 0.26
ring = np.sqrt((np.sqrt((xs - 0.62) ** 2 + (ys - 0.5) ** 2) - 0.26) ** 2 + (zs - 0.35) ** 2) - 0.1
sdf = np.minimum(sphere, ring).astype("<f4")
with open("scenes/assets/blob.vol", "wb") as f:
    f.write(b"VOL" + bytes([3]) + struct.pack("<iiiii", 1, nx, ny, nz, 1) + struct.pack("<6f", 0, 0, 0, 1, 1, 1))
    f.write(sdf.tobytes())

# A tangent-space normal map (64x64, 8-bit, stored raw: c = (n + 1) / 2): a 4x4 grid of round
# bumps whose normals tilt up to about 50 degrees, and a flat groove between them, so that a
# map read with the wrong axis order, sign or sRGB decoding shows.
n = 64
nm = np.zeros((n, n, 3), dtype=np.float32)
for y in range(n):
    for x in range(n):
        # Texel centres in [0, 1); rows from the top are v = 1 - y/n (Mitsuba's bitmap).
        u, v = (x + 0.5) / n, 1.0 - (y + 0.5) / n
        cu, cv = (u * 4) % 1 - 0.5, (v * 4) % 1 - 0.5
        r = math.hypot(cu, cv)
        if r < 0.4:
            # A spherical cap: the height falls off from the centre, so the normal leans out.
            k = 1.2 * r / 0.4
            nrm = np.array([cu / max(r, 1e-6) * k, cv / max(r, 1e-6) * k, 1.0])
        else:
            nrm = np.array([0.0, 0.0, 1.0])
        nrm /= np.linalg.norm(nrm)
        nm[y, x] = (nrm + 1) / 2
img = mi.Bitmap(nm).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=False)
img.write("scenes/assets/bumps_normal.png")

# Heterogeneous media: a smoke density (a cluster of Gaussian puffs, zero near the faces, so
# most of the box is thin) on a 24^3 grid, one channel, and a coloured albedo on a 6^3 grid,
# three channels (red to blue along x, greener with height).
def write_vol(path, data):
    nz_, ny_, nx_, ch = data.shape
    with open(path, "wb") as f:
        f.write(b"VOL" + bytes([3]) + struct.pack("<iiiii", 1, nx_, ny_, nz_, ch) + struct.pack("<6f", 0, 0, 0, 1, 1, 1))
        f.write(data.astype("<f4").tobytes())


n = 24
zs, ys, xs = np.meshgrid(*(np.linspace(0.5 / n, 1 - 0.5 / n, n),) * 3, indexing="ij")
density = np.zeros_like(xs)
for cx, cy, cz, r, a in [(0.5, 0.35, 0.5, 0.22, 1.0), (0.35, 0.6, 0.45, 0.16, 0.8), (0.65, 0.62, 0.58, 0.14, 1.3),
                         (0.5, 0.8, 0.5, 0.1, 0.6), (0.3, 0.3, 0.7, 0.1, 0.9)]:
    density += a * np.exp(-((xs - cx) ** 2 + (ys - cy) ** 2 + (zs - cz) ** 2) / (r * r))
write_vol("scenes/assets/smoke.vol", density[..., None])
m = 6
zs, ys, xs = np.meshgrid(*(np.linspace(0, 1, m),) * 3, indexing="ij")
albedo = np.stack([0.95 - 0.5 * xs, 0.4 + 0.5 * ys, 0.45 + 0.5 * xs], axis=-1)
write_vol("scenes/assets/albedo.vol", albedo)
# Curves (linearcurve): 24 strands rising from a ring, bending outward, 7 points each, their
# radius shrinking from 0.05 to 0.012; and a coil of 40 points of radius 0.06 around them.
lines = []
for k in range(24):
    a = 2 * math.pi * k / 24
    for i in range(7):
        s_ = i / 6
        rad = 0.25 + 0.9 * s_ * s_
        lines.append(f"{rad * math.cos(a):.5f} {1.6 * s_:.5f} {rad * math.sin(a):.5f} {0.05 - 0.038 * s_:.5f}")
    lines.append("")
with open("scenes/assets/tufts.txt", "w") as f:
    f.write("\n".join(lines))
with open("scenes/assets/coil.txt", "w") as f:
    for i in range(40):
        a = 2 * math.pi * i / 16
        f.write(f"{0.95 * math.cos(a):.5f} {0.1 + 0.02 * i:.5f} {0.95 * math.sin(a):.5f} 0.06\n")
# SGGX flakes (the sggx phase function's S, six channels: xx yy zz xy xz yz) on a 12^3 grid:
# fibres circling the vertical axis at the bottom (S = sigma^2 t t^T + (I - t t^T), t the fibre
# direction, sigma 0.15), surface-like flakes facing up at the top (S = n n^T + sigma^2 (I - n n^T),
# sigma 0.3), blended linearly in height; every matrix has largest eigenvalue 1.
m = 12
zs, ys, xs = np.meshgrid(*(np.linspace(0.5 / m, 1 - 0.5 / m, m),) * 3, indexing="ij")
flakes = np.zeros((m, m, m, 6))
eye = np.eye(3)
for k in range(m):
    for j in range(m):
        for i in range(m):
            x, y, z = xs[k, j, i] - 0.5, ys[k, j, i], zs[k, j, i] - 0.5
            t = np.array([-z, 0.25, x])
            t /= np.linalg.norm(t)
            fibre = 0.15 ** 2 * np.outer(t, t) + (eye - np.outer(t, t))
            n_ = np.array([0.0, 1.0, 0.0])
            surface = np.outer(n_, n_) + 0.3 ** 2 * (eye - np.outer(n_, n_))
            S = (1 - y) * fibre + y * surface
            flakes[k, j, i] = [S[0, 0], S[1, 1], S[2, 2], S[0, 1], S[0, 2], S[1, 2]]
write_vol("scenes/assets/flakes.vol", flakes)
print("wrote scenes/assets/sky.exr, tiles.png, knot.obj, knot.serialized, knot_colors.ply, blob.vol, bumps_normal.png, "
      "smoke.vol, albedo.vol, tufts.txt, coil.txt and flakes.vol")
