"""Renders Mitsuba 3 references for neumann's validation scenes and measures Mitsuba's own error.

For each scene in scenes/ (the three shared scenes, copied from ../shared/scenes, and neumann's
own) this writes references/<scene>.exr, a long Mitsuba render (float32 RGB, small resolution),
and records in references/references.json Mitsuba's relMSE and mean at the test sample count,
averaged over independent seeds, with its render time. tests/validation.rs renders the same scenes
with neumann at the same settings and asserts relMSE <= max_relmse_ratio x Mitsuba's (1.5, or
tighter where an issue asked for it) and the mean within max_mean_difference of the reference's:
0.5 %, or three standard deviations of Mitsuba's own image mean at the test spp where that is
more (measured over MEAN_SEEDS renders: scenes whose mean is carried by rare bright samples,
such as tiny lights seen in mirrors, scatter more than 0.5 % from run to run).

Run from the repository root with Mitsuba in a venv outside the repository:
    python3 -m venv ~/mitsuba-venv && ~/mitsuba-venv/bin/pip install mitsuba numpy
    ~/mitsuba-venv/bin/python tools/mitsuba/make_assets.py      # once: scenes/assets
    ~/mitsuba-venv/bin/python tools/mitsuba/references.py [scene ...]   # or --csv: rewrite the CSV
    ~/mitsuba-venv/bin/python tools/mitsuba/references.py --means [scene ...]  # only the spread of the mean
Variant: scalar_rgb (llvm_ad_rgb needs libLLVM; set NEUMANN_MI_VARIANT to use it)."""
import json
import os
import sys
import time

import numpy as np
import mitsuba as mi

mi.set_variant(os.environ.get("NEUMANN_MI_VARIANT", "scalar_rgb"))
mi.set_log_level(mi.LogLevel.Warn)

RES = 128
# scene: (reference spp, test spp, extra parameters, largest relMSE ratio to Mitsuba's that the
# validation accepts)
SCENES = {
    "cbox": (8192, 64, {}, 1.5),
    "cbox_spheres": (8192, 64, {}, 1.5),
    "furnace": (1024, 64, {}, 1.5),
    "veach_mis": (16384, 1024, {}, 1.5),  # the smallest light's highlights make the mean noisy: many spp
    "envmap": (4096, 64, {}, 1.5),
    "caustics": (16384, 256, {}, 1.5),
    "textures": (4096, 64, {}, 1.5),
    "volume": (4096, 128, {}, 1.5),
    # Small and many lights (light selection, cone sampling, Gaussian reconstruction).
    "small_lights": (16384, 64, {}, 1.2),
    "small_light_env": (16384, 256, {}, 1.2),
    "many_lights": (32768, 64, {}, 0.5),
    # Mitsuba conventions: moment and aov integrators, meshes without normals (OBJ, serialized),
    # rotated sphere textures, textured rough plastic, rawconstant, the orthographic sensor.
    "mitsuba_compat": (8192, 64, {}, 1.5),
    "orthographic": (4096, 64, {}, 1.5),
    # Projected light: textured spot, projectors (textured and constant).
    "projector": (4096, 64, {}, 1.5),
    # Textured roughness, specular reflectance, blend weight and mask opacity.
    "textured_params": (8192, 64, {}, 1.5),
    # Textured dielectric and conductor parameters (roughness, reflectance, transmittance,
    # eta, k). A texture replaced by a constant raises relMSE by 1.1-1.4x here (or shifts the
    # mean): the bound is tighter than the default.
    "textured_glass": (8192, 64, {}, 1.25),
    # Signed distance fields on a grid (sdfgrid), smooth and analytic shading normals.
    "sdfgrid": (8192, 64, {}, 1.5),
    # Tangent-space normal maps (normalmap) over rough plastic, diffuse and anisotropic metal.
    "normalmap": (8192, 64, {}, 1.5),
    # Bump maps (bumpmap) from a bitmap's luminance on a floor and a sphere.
    "bumpmap": (8192, 64, {}, 1.5),
    # The principled BSDF: metallic with clearcoat and anisotropy, transmission, sheen and
    # flatness with textured base colour and roughness, spec_tint; a principledthin leaf.
    "principled": (8192, 64, {}, 1.5),
    # Polarized plastic, unpolarized (Mitsuba's RGB variants): plain and textured, anisotropic.
    "pplastic": (8192, 64, {}, 1.5),
    # Measured BSDFs (RGL tensor files, synthetic: tools/mitsuba/make_measured.py): isotropic
    # and anisotropic (a quarter circle of incident azimuths, mirrored).
    "measured": (8192, 64, {}, 1.5),
    # Heterogeneous media: a gridvolume smoke with a coloured albedo grid behind a null
    # boundary, a constvolume inside a glass sphere, filling only part of it.
    # (128 spp: the glass sphere's caustic makes the mean at 64 spp swing by 0.3 %.)
    "heterogeneous": (8192, 128, {}, 1.5),
    # Spectral MIS (volpathmis): a three-channel extinction grid and a strongly chromatic
    # homogeneous sphere.
    "volpathmis": (8192, 64, {}, 1.5),
    # Phase functions: Rayleigh, a table over the deflection cosine (tabphase), and a blend of
    # a forward and a backward lobe weighted by a grid volume (blendphase), backlit.
    "phase": (4096, 128, {}, 1.5),
    # Round curves: tapered bent strands (linearcurve, diffuse) and a coil (bsplinecurve, rough gold).
    "curves": (8192, 64, {}, 1.5),
    # Mitsuba's hair BSDF on round B-spline curves: default brown, and blond with tilted scales.
    "hair": (8192, 64, {}, 1.5),
    # Mitsuba's ellipsoid primitives from a 3D-Gaussian file: analytic shells with adaptive
    # extents under a rotating, stretching to_world, and uv_sphere mesh shells.
    "ellipsoids": (8192, 64, {}, 1.5),
    # Polarizing elements in RGB (polarizer, circular, retarder) crossed by volpath's shadow
    # rays, under a timed_sunsky at the sensor's closed shutter (its sky; the sun off).
    "filters": (8192, 64, {}, 1.5),
    # Sun and sky (sunsky): a time record in a rotated frame, the sky in view, a low sun.
    "sunsky": (8192, 64, {}, 1.5),
    # Laid out as Blender's exporter writes scenes: named objects in the scene, a principal
    # point offset, a cube with face_normals, a flipped area rectangle with a spectral radiance.
    "blender_export": (8192, 64, {}, 1.5),
}
SEEDS = 4
# Renders at the test spp that measure the spread of Mitsuba's image mean (seeds 100, 101, …).
MEAN_SEEDS = 12


def relmse(img, ref):
    """Mean over pixels and channels of (img - ref)^2 / (ref^2 + 1e-2)."""
    return float(np.mean((img - ref) ** 2 / (ref ** 2 + 1e-2)))


def render(name, spp, seed, extra):
    params = dict(res=str(RES), spp=str(spp), **extra)
    scene = mi.load_file(f"scenes/{name}.xml", **params)
    start = time.time()
    img = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float32)[:, :, :3]
    return img, time.time() - start


CSV_FIELDS = ("res", "test_spp", "reference_spp", "mitsuba_relmse", "reference_mean", "mitsuba_samples_per_second",
              "max_relmse_ratio", "max_mean_difference")


def write_csv(db):
    """The figures the Rust validation reads (references/references.csv)."""
    with open("references/references.csv", "w") as f:
        f.write("scene," + ",".join(CSV_FIELDS) + "\n")
        for name in sorted(db):
            row = dict(db[name], max_relmse_ratio=SCENES[name][3],
                       max_mean_difference=max_mean_difference(db[name]))
            f.write(name + "," + ",".join(f"{row[k]:.6g}" for k in CSV_FIELDS) + "\n")


def max_mean_difference(entry):
    """The largest relative difference of the image mean from the reference's the validation
    accepts: 0.5 %, or three standard deviations of Mitsuba's own means where that is more."""
    runs = entry.get("mitsuba_mean_runs")
    if not runs:
        return 0.005
    return max(0.005, 3.0 * float(np.std(runs, ddof=1)) / entry["reference_mean"])


def measure_means(db, name):
    """Mitsuba's image mean at the test spp over MEAN_SEEDS seeds."""
    _, test_spp, extra, _ = SCENES[name]
    means = [float(render(name, test_spp, 100 + seed, extra)[0].mean()) for seed in range(MEAN_SEEDS)]
    db[name]["mitsuba_mean_runs"] = means
    sd = float(np.std(means, ddof=1)) / db[name]["reference_mean"]
    print(f"{name}: mean over {MEAN_SEEDS} runs at {test_spp} spp: relative sd {100 * sd:.3f} %, "
          f"tolerance {100 * max_mean_difference(db[name]):.3f} %", flush=True)


def main():
    args = sys.argv[1:]
    db_path = "references/references.json"
    db = json.load(open(db_path)) if os.path.exists(db_path) else {}
    if args == ["--csv"]:
        write_csv(db)
        return
    if args[:1] == ["--means"]:
        for name in args[1:] or list(SCENES):
            measure_means(db, name)
            with open(db_path, "w") as f:
                json.dump(db, f, indent=1, sort_keys=True)
            write_csv(db)
        return
    names = args or list(SCENES)
    for name in names:
        ref_spp, test_spp, extra, _ = SCENES[name]
        ref, ref_time = render(name, ref_spp, 1_000_003, extra)
        mi.Bitmap(ref).write(f"references/{name}.exr")
        errors, means, times = [], [], []
        for seed in range(SEEDS):
            img, t = render(name, test_spp, seed, extra)
            errors.append(relmse(img, ref))
            means.append(float(img.mean()))
            times.append(t)
        db[name] = {
            "res": RES,
            "reference_spp": ref_spp,
            "test_spp": test_spp,
            "parameters": extra,
            "mitsuba_relmse": float(np.mean(errors)),
            "mitsuba_relmse_runs": errors,
            "mitsuba_mean": float(np.mean(means)),
            "reference_mean": float(ref.mean()),
            "mitsuba_seconds": float(np.median(times)),
            "mitsuba_samples_per_second": RES * RES * test_spp / float(np.median(times)),
            "mitsuba_variant": mi.variant(),
            "mitsuba_version": mi.__version__,
        }
        measure_means(db, name)
        print(f"{name}: reference {ref_spp} spp in {ref_time:.1f} s; at {test_spp} spp relMSE "
              f"{db[name]['mitsuba_relmse']:.4g} (runs {', '.join(f'{e:.3g}' for e in errors)}), "
              f"{db[name]['mitsuba_samples_per_second'] / 1e6:.2f} M samples/s", flush=True)
        with open(db_path, "w") as f:
            json.dump(db, f, indent=1, sort_keys=True)
        write_csv(db)


if __name__ == "__main__":
    main()
