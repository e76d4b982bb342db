"""Writes two small synthetic measured materials (scenes/assets/measured_iso.bsdf and
measured_aniso.bsdf) in the RGB tensor format of the RGL material database, which Mitsuba's
`measured` plugin reads: no measurement is available offline, so the tables follow the same
definitions from an analytic GGX microfacet model (Dupuy & Jakob 2018, "An Adaptive
Parameterization for Efficient Material Acquisition and Rendering"):

- ndf[phi_m][theta_m]: D(m) on the unit coordinates u_theta = sqrt(2 theta / pi),
  u_phi = (phi + pi) / 2 pi;
- sigma[phi][theta]: the projected area cos(theta) (1 + Lambda) of the viewing direction;
- vndf[phi_i][theta_i][phi_m][theta_m]: the visible normals' density in unit coordinates,
  D(m) max(0, wi.m) / sigma(wi) times the Jacobian 2 pi^2 u_theta sin(theta_m) (the azimuth of m
  relative to phi_i for the isotropic material);
- rgb[phi_i][theta_i][3][y][x] over the sample square: a smooth colour that varies over the square
  and brightens toward grazing incidence (synthetic, at most 1, so the BRDF conserves energy);
- luminance[phi_i][theta_i][y][x]: the luminance of rgb;
- jacobian = 1: the BRDF is rgb * D(m) / (4 sigma(wi)).

The isotropic material tabulates one azimuth (phi_i = [0]); the anisotropic one (alpha 0.12 along
x, 0.45 along y) tabulates a quarter circle, phi_i from -pi to -pi/2, which Mitsuba mirrors
directions into ("reduction 4"). Both renderers read the same files, so the comparison of
images and of eval/pdf values is exact whatever the tables hold.

Run with the venv that renders the references: python tools/mitsuba/make_measured.py
(`--spectral PATH`: the isotropic material with spectra, see write_spectral)."""
import math

import numpy as np
from mitsuba.python import tensor_io

N_M = 12      # unit-coordinate grid of m (and of ndf, sigma): N_M x N_M
N_S = 10      # sample-square grid of rgb and luminance
THETA_I = np.radians([0.0, 20.0, 40.0, 60.0, 80.0]).astype(np.float32)


def ggx(alpha_x, alpha_y):
    def d(m):
        x, y, z = m
        if z <= 0:
            return 0.0
        t = (x / alpha_x) ** 2 + (y / alpha_y) ** 2 + z * z
        return 1.0 / (math.pi * alpha_x * alpha_y * t * t)

    def sigma(w):
        x, y, z = w
        if z <= 0:
            return 0.0
        a2t2 = ((alpha_x * x) ** 2 + (alpha_y * y) ** 2) / (z * z)
        lam = (-1.0 + math.sqrt(1.0 + a2t2)) / 2.0
        return z * (1.0 + lam)

    return d, sigma


def direction(theta, phi):
    return (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta))


def u_to_angles(ux, uy):
    return ux * ux * math.pi / 2, (2 * uy - 1) * math.pi


def tables(alpha_x, alpha_y, phi_i, isotropic, tint):
    d, sigma = ggx(alpha_x, alpha_y)
    grid = np.linspace(0, 1, N_M)
    ndf = np.zeros((N_M, N_M), np.float32)
    sig = np.zeros((N_M, N_M), np.float32)
    for j, uy in enumerate(grid):
        for i, ux in enumerate(grid):
            theta, phi = u_to_angles(ux, uy)
            ndf[j, i] = d(direction(theta, phi))
            sig[j, i] = sigma(direction(theta, phi))
    vndf = np.zeros((len(phi_i), len(THETA_I), N_M, N_M), np.float32)
    rgb = np.zeros((len(phi_i), len(THETA_I), 3, N_S, N_S), np.float32)
    s = np.linspace(0, 1, N_S)
    sx, sy = np.meshgrid(s, s)
    for a, pi_ in enumerate(phi_i):
        for b, ti in enumerate(THETA_I):
            wi = direction(ti, pi_)
            for j, uy in enumerate(grid):
                for i, ux in enumerate(grid):
                    theta, phi = u_to_angles(ux, uy)
                    m = direction(theta, phi + (pi_ if isotropic else 0.0))
                    cos = max(0.0, sum(p * q for p, q in zip(wi, m)))
                    jac = 2 * math.pi ** 2 * ux * math.sin(theta)
                    vndf[a, b, j, i] = d(m) * cos / sigma(wi) * jac
            grazing = (ti / (math.pi / 2)) ** 3
            for c in range(3):
                base = tint[c] * (0.75 + 0.25 * np.cos(math.pi * sx * (c + 1) / 2)) * (0.8 + 0.2 * sy)
                rgb[a, b, c] = np.minimum(base + (1 - base) * grazing * (0.5 + 0.5 * sx), 1.0)
    lum = (0.2126 * rgb[:, :, 0] + 0.7152 * rgb[:, :, 1] + 0.0722 * rgb[:, :, 2]).astype(np.float32)
    return ndf, sig, vndf, rgb, lum


def write(path, description, alpha_x, alpha_y, phi_i, isotropic, tint):
    ndf, sig, vndf, rgb, lum = tables(alpha_x, alpha_y, phi_i, isotropic, tint)
    tensor_io.write(
        path,
        description=description,
        phi_i=np.array(phi_i, np.float32),
        theta_i=THETA_I,
        ndf=ndf,
        sigma=sig,
        vndf=vndf,
        rgb=rgb,
        luminance=lum,
        jacobian=np.array([1], np.uint8),
    )


def write_spectral(path):
    """The isotropic material's tables with spectra instead of RGB (48 wavelengths, 360-830 nm),
    for checking the reduction of spectral files to RGB against Mitsuba's spectral variants (not
    a validation asset: Mitsuba's RGB variants refuse spectral files)."""
    ndf, sig, vndf, rgb, lum = tables(0.3, 0.3, [0.0], True, (0.95, 0.64, 0.54))
    lambdas = np.arange(360, 831, 10).astype(np.float32)
    s = np.linspace(0, 1, N_S)
    sx, sy = np.meshgrid(s, s)
    spectra = np.zeros((1, len(THETA_I), len(lambdas), N_S, N_S), np.float32)
    for b in range(len(THETA_I)):
        for k, lam in enumerate(lambdas):
            bump = math.exp(-0.5 * ((lam - (520 + 120 * 0.5)) / 45) ** 2)
            spectra[0, b, k] = 0.25 + 0.5 * bump * (0.6 + 0.4 * sx) + 0.15 * sy * (lam > 600)
    lum = spectra.mean(axis=2).astype(np.float32)
    tensor_io.write(path, description="synthetic isotropic GGX (alpha 0.3), spectral", phi_i=np.array([0.0], np.float32),
                    theta_i=THETA_I, ndf=ndf, sigma=sig, vndf=vndf, spectra=spectra, luminance=lum,
                    wavelengths=lambdas, jacobian=np.array([1], np.uint8))


def main():
    import sys
    if sys.argv[1:2] == ["--spectral"]:
        write_spectral(sys.argv[2])
        return
    write("scenes/assets/measured_iso.bsdf", "synthetic isotropic GGX (alpha 0.3), copper tint",
          0.3, 0.3, [0.0], True, (0.95, 0.64, 0.54))
    write("scenes/assets/measured_aniso.bsdf", "synthetic anisotropic GGX (alpha 0.12 x 0.45), blue tint",
          0.12, 0.45, [-math.pi, -0.75 * math.pi, -0.5 * math.pi], False, (0.35, 0.55, 0.9))


if __name__ == "__main__":
    main()
