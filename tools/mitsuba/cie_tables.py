"""Prints the CIE 1931 2-degree colour matching functions and the D65 illuminant every 5 nm from
360 to 830 nm as Mitsuba 3 tabulates them, as the Rust table in src/math/spectrum.rs (used to
reduce `<spectrum>` values given as wavelength:value pairs to linear sRGB, the way Mitsuba's RGB
variants do). Run with Mitsuba installed in a venv outside the repository."""
import mitsuba as mi

mi.set_variant("scalar_spectral")
mi.set_log_level(mi.LogLevel.Error)
d65 = mi.load_dict({"type": "d65"})
si = mi.SurfaceInteraction3f()
for lam in range(360, 831, 5):
    si.wavelengths = mi.Spectrum(lam)
    x, y, z = (float(v) for v in mi.cie1931_xyz(lam))
    print(f"    [{x:.6e}, {y:.6e}, {z:.6e}, {float(d65.eval(si)[0]):.6e}], // {lam} nm")
