"""Times Mitsuba 3's vectorized ray queries (llvm_ad_rgb: wavefronts of rays, sixteen per AVX-512
instruction, through Embree on the CPU) on the mesh and rays `neumann bench --export DIR` wrote,
so that they compare with neumann's single-ray figures on identical data:

    cargo run --release -- bench --mesh MESH --no-cbox --export /tmp/rays
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        ~/mitsuba-venv/bin/python tools/mitsuba/rays.py /tmp/rays

Prints Mrays/s with all threads for `ray_intersect_preliminary` (distance, primitive and
barycentrics: neumann's `intersect_hit`), `ray_intersect` (with the surface interaction) and
`ray_test` (shadow rays), best of three, after one untimed pass that compiles the kernels. The
formats of mesh.bin and rays.bin are in neumann's `bench.rs::write_export`."""
import os
import struct
import sys
import tempfile
import time

import drjit as dr
import mitsuba as mi
import numpy as np


def main():
    folder = sys.argv[1]
    mesh = open(os.path.join(folder, "mesh.bin"), "rb").read()
    nv, nt = struct.unpack_from("<II", mesh)
    verts = np.frombuffer(mesh, "<f4", 3 * nv, 8).reshape(nv, 3)
    faces = np.frombuffer(mesh, "<u4", 3 * nt, 8 + 12 * nv).reshape(nt, 3)
    rays = open(os.path.join(folder, "rays.bin"), "rb").read()
    (nr,) = struct.unpack_from("<I", rays)
    r = np.frombuffer(rays, "<f4", 6 * nr, 4).reshape(nr, 6)

    mi.set_variant("llvm_ad_rgb")
    with tempfile.TemporaryDirectory() as tmp:
        ply = os.path.join(tmp, "mesh.ply")
        with open(ply, "wb") as f:
            f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {nv}\nproperty float x\n"
                     f"property float y\nproperty float z\nelement face {nt}\n"
                     "property list uchar int vertex_indices\nend_header\n").encode())
            f.write(verts.astype("<f4").tobytes())
            rows = np.empty(nt, dtype=[("n", "u1"), ("i", "<i4", 3)])
            rows["n"], rows["i"] = 3, faces
            f.write(rows.tobytes())
        scene = mi.load_dict({"type": "scene", "mesh": {"type": "ply", "filename": ply}})
    ray = mi.Ray3f(mi.Point3f(r[:, 0], r[:, 1], r[:, 2]), mi.Vector3f(r[:, 3], r[:, 4], r[:, 5]))
    print(f"Mitsuba {mi.__version__} llvm_ad_rgb: {nt} triangles, {nr} rays")
    print(f"{'rays (Mrays/s)':<28} {'all threads':>12}   hit rate")
    for name, query in [
        ("incoherent closest-hit", lambda: scene.ray_intersect_preliminary(ray).t),
        ("  + surface interaction", lambda: scene.ray_intersect(ray).t),
        ("incoherent shadow (test)", lambda: scene.ray_test(ray)),
    ]:
        best, hits = 0.0, 0
        for k in range(4):
            dr.eval(ray)
            dr.sync_thread()
            start = time.time()
            out = query()
            dr.eval(out)
            dr.sync_thread()
            if k > 0:
                best = max(best, nr / (time.time() - start) / 1e6)
            hits = dr.count(out if isinstance(out, mi.Bool) else dr.isfinite(out))[0]
        print(f"{name:<28} {best:>12.2f}   {100.0 * hits / nr:.0f} %")


if __name__ == "__main__":
    main()
