"""Writes scenes/assets/ellipsoids.ply, a small point file of 3D Gaussians in the layout 3D
Gaussian splatting writes (x y z nx ny nz f_dc_0..2 f_rest_0..8 opacity scale_0..2 rot_0..3,
binary little-endian floats; scales as logarithms, opacities as logits, quaternions w x y z),
and prints ray hits that Mitsuba 3.9.1 computes on it for src/geometry/ellipsoids.rs's tests:
the analytic `ellipsoids` and the `ellipsoidsmesh` (uv_sphere shells), both placed by a
to_world, with scale_factor, extent and extent_adaptive_clamping.

    ~/mitsuba-venv/bin/python tools/mitsuba/make_ellipsoids.py"""
import struct

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
rng = np.random.default_rng(7)
N = 48
names = ["x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"]
names += ["f_rest_%d" % k for k in range(9)] + ["opacity", "scale_0", "scale_1", "scale_2"]
names += ["rot_0", "rot_1", "rot_2", "rot_3"]
rows = []
for i in range(N):
    # A loose ring of petals around a core, in a 2-unit box.
    a = 2 * np.pi * i / N
    r = 0.35 + 0.55 * rng.random()
    centre = [r * np.cos(a), r * np.sin(a), 0.35 * rng.normal()]
    scale = np.log([0.06 + 0.1 * rng.random(), 0.03 + 0.05 * rng.random(), 0.02 + 0.04 * rng.random()])
    q = rng.normal(size=4)
    q *= (0.5 + rng.random()) / np.linalg.norm(q)  # not normalized: the loader normalizes
    sh = rng.normal(scale=0.5, size=12)
    # Logits from -6 (opacity 0.0025: no shell with adaptive clamping) to 4.
    opacity = -6 + 10 * rng.random()
    rows.append(centre + [0, 0, 0] + list(sh) + [opacity] + list(scale) + list(q))
path = "scenes/assets/ellipsoids.ply"
with open(path, "wb") as f:
    header = "ply\nformat binary_little_endian 1.0\nelement vertex %d\n" % N
    header += "".join("property float %s\n" % n for n in names) + "end_header\n"
    f.write(header.encode())
    for row in rows:
        f.write(struct.pack("<%df" % len(row), *row))
print("wrote", path)

to_world = mi.ScalarTransform4f().translate([0.2, -0.1, 0.4]).rotate([1, 1, 0], 30).scale(1.3)
common = {"filename": path, "to_world": to_world, "scale_factor": 0.8, "extent": 2.5,
          "extent_adaptive_clamping": True}
for shape in ["ellipsoids", "ellipsoidsmesh"]:
    extra = {"shell": "uv_sphere"} if shape == "ellipsoidsmesh" else {}
    scene = mi.load_dict({"type": "scene", "s": dict(type=shape, **common, **extra)})
    print("//", shape)
    hits = misses = 0
    for k in range(400):
        o = rng.normal(size=3)
        o = 4 * o / np.linalg.norm(o)
        target = rng.normal(scale=0.5, size=3) + [0.2, -0.1, 0.4]
        if k % 10 == 0:
            # From inside the cloud.
            o = target + rng.normal(scale=0.3, size=3)
        d = target - o
        d /= np.linalg.norm(d)
        si = scene.ray_intersect(mi.Ray3f(mi.Point3f(o), mi.Vector3f(d)))
        o32 = [float(np.float32(v)) for v in o]
        d32 = [float(np.float32(v)) for v in d]
        if si.is_valid():
            if hits < 16:
                n = si.n
                print("([%.7f, %.7f, %.7f], [%.7f, %.7f, %.7f], Some((%.6f, [%.6f, %.6f, %.6f], %d)))," %
                      (*o32, *d32, si.t, n[0], n[1], n[2], si.prim_index))
            hits += 1
        else:
            if misses < 6:
                print("([%.7f, %.7f, %.7f], [%.7f, %.7f, %.7f], None)," % (*o32, *d32))
            misses += 1
    print("// %d hits, %d misses" % (hits, misses))
