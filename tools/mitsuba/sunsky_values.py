"""Mitsuba 3.9.1's `sunsky` radiance (RGB variant) for a few emitters and directions, and the sun
directions of time/location records: the numbers the unit tests of src/light/sunsky.rs hold.

    ~/mitsuba-venv/bin/python tools/mitsuba/sunsky_values.py
"""
import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

EMITTERS = [
    {},
    {"sun_direction": [0.3, -0.5, 0.4], "turbidity": 4.5, "albedo": {"type": "rgb", "value": [0.1, 0.5, 0.9]},
     "sun_scale": 2.0, "sky_scale": 0.5, "sun_aperture": 2.0},
    {"sun_direction": [-0.2, 0.9, 0.1], "complex_sun": True, "sun_aperture": 5.0, "turbidity": 7.2, "albedo": 0.8,
     "to_world": mi.ScalarTransform4f().rotate([1, 0, 0], -90)},
    {"sun_direction": [1.0, 0.2, 0.01], "turbidity": 1.0},
    {"latitude": 48.85, "longitude": 2.35, "timezone": 1, "year": 2024, "month": 3, "day": 20, "hour": 9.5,
     "minute": 30, "second": 12, "turbidity": 10.0, "albedo": 0.0},
    {"latitude": -33.9, "longitude": 18.4, "timezone": 2, "year": 1999, "month": 12, "day": 31, "hour": 17,
     "complex_sun": True},
]
DIRECTIONS = [(0, 0, 1), (1, 0, 0.2), (0, 1, 0.5), (-0.3, 0.2, 0.9), (0.5, -0.5, 0.05), (0.2, 0.1, -0.3), (0, 1, -0.5)]


def fmt(v):
    return "[" + ", ".join(f"{x:.7e}" for x in v) + "]"


for props in EMITTERS:
    d = {"type": "sunsky", **props}
    e = mi.load_dict(d)
    sun = np.array(mi.traverse(e)["sun_direction"], dtype=np.float64)
    print("emitter", {k: v for k, v in props.items() if k != "to_world"}, "sun", fmt(sun))
    dirs = [np.array(v, dtype=np.float64) / np.linalg.norm(v) for v in DIRECTIONS]
    # In the sun, and (complex sun) across its disk.
    frame = mi.Frame3f(mi.Vector3f(sun))
    half = np.radians(0.5 * props.get("sun_aperture", 0.5358))
    for f in [0.0, 0.5, 0.9, 1.1]:
        a = f * half
        w = np.array(frame.to_world(mi.Vector3f(np.sin(a), 0.0, np.cos(a))), dtype=np.float64)
        dirs.append(w / np.linalg.norm(w))
    for w in dirs:
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(-w)
        print("  ", fmt(w), fmt(np.array(e.eval(si))))
