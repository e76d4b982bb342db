"""Writes src/light/sunsky.bin, the tables of neumann's `sunsky` emitter, from the Hošek–Wilkie
datasets that Mitsuba 3.9.1 ships (data/sunsky/, BSD licence of Hošek and Wilkie, repeated in
src/light/SUNSKY_LICENSE), in the RGB form Mitsuba's RGB variants use:

  sky_params [turbidity 10][albedo 2][control point 6][channel 3][parameter 9]  (sky_params_rgb)
  sky_rad    [turbidity 10][albedo 2][control point 6][channel 3]               (sky_rad_rgb)
  sun_rad    [turbidity 10][segment 45][channel 3][power of x 4][power of cos ψ 6] (sun_rad_rgb,
             the `complex_sun` model, limb darkening included)
  sun_mean   [turbidity 10][elevation 30][channel 3]: the simple sun's radiance, W m⁻² sr⁻¹, as
             Mitsuba's RGB `sunsky` evaluates it at the default aperture (0.5358°) for the sun at
             elevation 2°, 5°, …, 89° and integer turbidity: its spectral irradiance table
             (sampling_data.bin) reduced to linear sRGB by Mitsuba's own response curves, measured
             here through the plugin itself (eval at the sun's centre, sky off).

All little-endian f32 after the 16-byte magic b"neumann-sunsky01" (Mitsuba reads the f64
datasets into single precision too).

    ~/mitsuba-venv/bin/python tools/mitsuba/sunsky_data.py
"""
import os
import sys

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
DATA = os.path.join(os.path.dirname(mi.__file__), "data", "sunsky")
OUT = os.path.join(os.path.dirname(__file__), "..", "..", "src", "light", "sunsky.bin")


def field(path, name):
    return np.array(mi.tensor_io.read(os.path.join(DATA, path))[name], dtype=np.float64)


def sun_mean():
    table = np.zeros((10, 30, 3))
    for t in range(10):
        for k in range(30):
            eta = np.radians(2.0 + 3.0 * k)
            d = [np.cos(eta), 0.0, np.sin(eta)]
            e = mi.load_dict({"type": "sunsky", "sun_direction": mi.Vector3f(d), "turbidity": 1.0 + t, "sky_scale": 0.0})
            si = mi.SurfaceInteraction3f()
            si.wi = mi.Vector3f(-np.array(d, dtype=np.float32))
            table[t, k] = np.array(e.eval(si))
    return table


def main():
    parts = [
        ("sunsky_datasets.bin", "sky_params_rgb", (10, 2, 6, 3, 9)),
        ("sunsky_datasets.bin", "sky_rad_rgb", (10, 2, 6, 3)),
        ("sunsky_datasets.bin", "sun_rad_rgb", (10, 45, 3, 4, 6)),
    ]
    blobs = []
    for path, name, shape in parts:
        a = field(path, name)
        assert a.shape == shape, (name, a.shape)
        blobs.append(a.astype("<f4").tobytes())
    mean = sun_mean()
    # Low suns have negative blue (and green) components in linear sRGB; Mitsuba keeps them.
    assert np.all(mean[:, 1:, 0] > 0), "the sun came out black"
    blobs.append(mean.astype("<f4").tobytes())
    with open(OUT, "wb") as f:
        f.write(b"neumann-sunsky01")
        for b in blobs:
            f.write(b)
    print(f"wrote {os.path.normpath(OUT)} ({16 + sum(len(b) for b in blobs)} bytes)", file=sys.stderr)


if __name__ == "__main__":
    main()
