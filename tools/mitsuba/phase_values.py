"""Mitsuba 3's phase function densities at a few direction pairs, for the unit test
`matches_mitsuba_densities` in src/medium/phase/mod.rs (which holds the printed numbers), and
the SGGX phase function's densities and projected areas for `matches_mitsuba` in
src/medium/phase/sggx.rs.

    ~/mitsuba-venv/bin/python tools/mitsuba/phase_values.py

Mitsuba's convention: mi.wi points away from the scattering point, back along the path
(neumann's `wo`); the plugin's `wo` is the scattered direction (neumann's `wi`)."""
import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

PHASES = [
    {"type": "rayleigh"},
    {"type": "tabphase", "values": "1.5, 0.3, 0.2 0.3, 0.8, 3, 10"},
    {"type": "blendphase", "weight": 0.3, "phase1": {"type": "hg", "g": 0.6}, "phase2": {"type": "rayleigh"}},
    {"type": "blendphase", "weight": {"type": "constvolume", "value": {"type": "rgb", "value": [0.2, 0.4, 0.9]}},
     "phase1": {"type": "isotropic"}, "phase2": {"type": "tabphase", "values": "0, 1"}},
]
PAIRS = [((0.0, 0.0, 1.0), (0.0, 0.0, -1.0)), ((0.0, 0.0, 1.0), (0.0, 0.0, 1.0)),
         ((0.3, -0.5, 0.81), (0.7, 0.1, -0.2)), ((0.6, 0.0, 0.8), (0.0, 1.0, 0.0)), ((1.0, 2.0, 3.0), (-1.0, 0.5, 0.2))]

ctx = mi.PhaseFunctionContext(None)
m = mi.MediumInteraction3f()
m.p = mi.Point3f(0.2, 0.3, 0.4)
for d in PHASES:
    phase = mi.load_dict(d)
    row = []
    for wi, wo in PAIRS:
        m.wi = mi.Vector3f(wi) / (sum(c * c for c in wi) ** 0.5)
        row.append(phase.eval_pdf(ctx, m, mi.Vector3f(wo) / (sum(c * c for c in wo) ** 0.5))[1])
    print(d["type"], ", ".join(f"{v:.7g}" for v in row))

# SGGX: one texel of S = [xx, yy, zz, xy, xz, yz] (a grid of six channels, the only form
# Mitsuba 3.9.1 reads); per matrix, the densities at PAIRS, then the projected areas toward
# each pair's first direction.
SGGX = [[1, 1, 1, 0, 0, 0], [1, 0.2, 0.05, 0, 0, 0], [0.6, 0.5, 0.3, 0.2, -0.1, 0.15], [2.5, 0.4, 1.2, 0.3, 0.5, -0.2]]
for s in SGGX:
    phase = mi.load_dict({"type": "sggx", "S": {"type": "gridvolume",
                                                 "data": mi.TensorXf(np.array(s, dtype=np.float32).reshape(1, 1, 1, 6))}})
    row, areas = [], []
    for wi, wo in PAIRS:
        m.wi = mi.Vector3f(wi) / (sum(c * c for c in wi) ** 0.5)
        row.append(phase.eval_pdf(ctx, m, mi.Vector3f(wo) / (sum(c * c for c in wo) ** 0.5))[1])
        areas.append(phase.projected_area(m))
    print("sggx", s, ", ".join(f"{v:.7g}" for v in row), "| areas", ", ".join(f"{v:.7g}" for v in areas))
