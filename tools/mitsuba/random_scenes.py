"""Differential testing against Mitsuba 3: random small scenes rendered by both, means compared.

Each scene (seeded, so reproducible by its number) has 1–4 random shapes (sphere, rectangle,
cube, disk, cylinder, the knot OBJ) over a floor, random BSDFs of 18 kinds (nested blends, masks,
two-sided, normal and bump maps, textured parameters), 1–2 random lights of 10 kinds (point, spot
and textured spot, area rectangle, textured area, area sphere, directional, constant, envmap,
sunsky), a random integrator (path, direct, volpath with homogeneous media, ptracer), sensor
(perspective, thin lens, orthographic) and filter. Mitsuba (`scalar_rgb`) and neumann render it
at the same spp with two seeds each; a scene is flagged MISMATCH when the means differ by more
than 4× the seeds' spread and 1 %. A flagged scene is then bisected by hand (drop one element at a
time) down to an analytic case: the differences found so far were neumann's (fixed) or Mitsuba
3.9.1's own, listed in the README ("Mitsuba 3 scenes"), which this generator avoids: fractional
`mask` opacity under `path`, `blendbsdf` of a delta and a smooth lobe, `direct` with several
emitter samples and a delta light, `ptracer` under a rotated envmap, non-unit rotation axes.

Run from the repository root after `cargo build --release`, with Mitsuba in a venv outside it:
    ~/mitsuba-venv/bin/python tools/mitsuba/random_scenes.py [--first N] [--count K] [--spp S] [--keep DIR]
(--keep writes each scene there as sK.xml for bisecting; default a temporary folder.)"""
import argparse
import os
import random
import subprocess
import sys
import tempfile

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
mi.set_log_level(mi.LogLevel.Error)
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
ASSETS = os.path.join(ROOT, "scenes", "assets")
NEUMANN = os.path.join(ROOT, "target", "release", "neumann")


def rgb(r, lo=0.05, hi=0.95):
    return ','.join(f'{r.uniform(lo, hi):.3f}' for _ in range(3))

def tex(r, name, lo=0.05, hi=0.95, scalar=False):
    k = r.random()
    if k < 0.6:
        if scalar:
            return f'<float name="{name}" value="{r.uniform(lo, hi):.3f}"/>'
        return f'<rgb name="{name}" value="{rgb(r, lo, hi)}"/>'
    if k < 0.8:
        c0 = f'<float name="color0" value="{r.uniform(lo, hi):.3f}"/>' if scalar else f'<rgb name="color0" value="{rgb(r, lo, hi)}"/>'
        c1 = f'<float name="color1" value="{r.uniform(lo, hi):.3f}"/>' if scalar else f'<rgb name="color1" value="{rgb(r, lo, hi)}"/>'
        return f'<texture type="checkerboard" name="{name}">{c0}{c1}<transform name="to_uv"><scale x="{r.randint(1,6)}" y="{r.randint(1,6)}"/></transform></texture>'
    if scalar:
        return f'<float name="{name}" value="{r.uniform(lo, hi):.3f}"/>'
    return f'<texture type="bitmap" name="{name}"><string name="filename" value="{ASSETS}/tiles.png"/></texture>'

def bsdf(r, depth=0):
    kinds = ['diffuse', 'roughplastic', 'plastic', 'conductor', 'roughconductor', 'dielectric', 'roughdielectric',
             'thindielectric', 'principled', 'twosided', 'blendbsdf', 'mask', 'pplastic', 'principledthin', 'null',
             'normalmap', 'bumpmap', 'texrough']
    if depth == 1:
        kinds = kinds[:9] + ['principled']
    if depth == 2:
        kinds = ['diffuse', 'roughplastic', 'plastic', 'conductor', 'roughconductor']
    if depth >= 3:
        kinds = ['diffuse', 'roughplastic', 'roughconductor', 'roughdielectric']
    k = r.choice(kinds)
    dist = f'<string name="distribution" value="{r.choice(["beckmann", "ggx"])}"/>'
    alpha = r.uniform(0.02, 0.6)
    if k == 'diffuse':
        return f'<bsdf type="diffuse">{tex(r, "reflectance")}</bsdf>'
    if k == 'plastic':
        return f'<bsdf type="plastic"><rgb name="diffuse_reflectance" value="{rgb(r)}"/><float name="int_ior" value="{r.uniform(1.2, 2):.3f}"/><boolean name="nonlinear" value="{r.choice(["true","false"])}"/></bsdf>'
    if k == 'roughplastic':
        return f'<bsdf type="roughplastic">{dist}<float name="alpha" value="{alpha:.3f}"/><rgb name="diffuse_reflectance" value="{rgb(r)}"/><boolean name="nonlinear" value="{r.choice(["true","false"])}"/></bsdf>'
    if k == 'pplastic':
        return f'<bsdf type="pplastic"><rgb name="diffuse_reflectance" value="{rgb(r)}"/><float name="alpha" value="{alpha:.3f}"/></bsdf>'
    if k == 'conductor':
        return f'<bsdf type="conductor"><string name="material" value="{r.choice(["Au","Cu","Al","Ag","Cr","none"])}"/></bsdf>'
    if k == 'roughconductor':
        an = f'<float name="alpha_u" value="{alpha:.3f}"/><float name="alpha_v" value="{r.uniform(0.02,0.6):.3f}"/>' if r.random() < 0.3 else f'<float name="alpha" value="{alpha:.3f}"/>'
        return f'<bsdf type="roughconductor">{dist}{an}<string name="material" value="{r.choice(["Au","Cu","Al","Ag","Cr"])}"/><boolean name="sample_visible" value="{r.choice(["true","false"])}"/></bsdf>'
    if k == 'dielectric':
        return f'<bsdf type="dielectric"><float name="int_ior" value="{r.uniform(1.1, 2.2):.3f}"/></bsdf>'
    if k == 'roughdielectric':
        return f'<bsdf type="roughdielectric">{dist}<float name="alpha" value="{alpha:.3f}"/><float name="int_ior" value="{r.uniform(1.1, 2.2):.3f}"/></bsdf>'
    if k == 'thindielectric':
        return f'<bsdf type="thindielectric"><float name="int_ior" value="{r.uniform(1.1, 2.2):.3f}"/></bsdf>'
    if k == 'principled':
        p = ''.join(f'<float name="{n}" value="{r.uniform(0, 1):.3f}"/>' for n in r.sample(['metallic','specular','roughness','spec_tint','anisotropic','sheen','sheen_tint','clearcoat','clearcoat_gloss','spec_trans'], 5))
        return f'<bsdf type="principled">{tex(r, "base_color")}{p}</bsdf>'
    if k == 'principledthin':
        p = ''.join(f'<float name="{n}" value="{r.uniform(0, 1):.3f}"/>' for n in r.sample(['roughness','spec_tint','anisotropic','sheen','sheen_tint','spec_trans','diff_trans','flatness'], 4))
        return f'<bsdf type="principledthin">{tex(r, "base_color")}{p}</bsdf>'
    if k == 'twosided':
        return f'<bsdf type="twosided">{r.choice([bsdf_diffuse(r), bsdf(r, 2)])}</bsdf>'
    if k == 'blendbsdf':
        return f'<bsdf type="blendbsdf">{tex(r, "weight", 0.0, 1.0, True)}{bsdf(r, 3)}{bsdf(r, 3)}</bsdf>'
    if k == 'mask':
        op = f'<texture type="checkerboard" name="opacity"><float name="color0" value="0"/><float name="color1" value="1"/><transform name="to_uv"><scale x="{r.randint(2,8)}" y="{r.randint(2,8)}"/></transform></texture>'
        return f'<bsdf type="mask">{op}{bsdf(r, 1)}</bsdf>'
    if k == 'null':
        return '<bsdf type="null"/>'
    if k == 'normalmap':
        return f'<bsdf type="normalmap"><texture type="bitmap" name="normalmap"><string name="filename" value="{ASSETS}/bumps_normal.png"/><boolean name="raw" value="true"/></texture>{bsdf(r, 2)}</bsdf>'
    if k == 'bumpmap':
        return f'<bsdf type="bumpmap"><texture type="bitmap"><string name="filename" value="{ASSETS}/tiles.png"/><boolean name="raw" value="true"/></texture><float name="scale" value="{r.uniform(0.1, 2):.2f}"/>{bsdf(r, 2)}</bsdf>'
    if k == 'texrough':
        return f'<bsdf type="roughconductor">{dist}<texture type="bitmap" name="alpha"><string name="filename" value="{ASSETS}/tiles.png"/></texture><string name="material" value="{r.choice(["Au","Cu","Al"])}"/></bsdf>'

def bsdf_diffuse(r):
    return f'<bsdf type="diffuse">{tex(r, "reflectance")}</bsdf>'

def shape(r, i, volumes=False):
    k = r.choice(['sphere', 'rectangle', 'cube', 'disk', 'cylinder', 'obj'])
    s = r.uniform(0.3, 0.8)
    ax = np.array([r.random(), r.random(), r.random()]) + 1e-3; ax /= np.linalg.norm(ax)
    t = f'<transform name="to_world"><scale value="{s:.3f}"/><rotate x="{ax[0]:.6f}" y="{ax[1]:.6f}" z="{ax[2]:.6f}" angle="{r.uniform(0,360):.1f}"/><translate x="{r.uniform(-1,1):.2f}" y="{r.uniform(-0.6,0.8):.2f}" z="{r.uniform(-1,0.5):.2f}"/></transform>'
    extra = f'<string name="filename" value="{ASSETS}/knot.obj"/>' if k == 'obj' else ''
    if k == 'obj':
        t = t.replace(f'<scale value="{s:.3f}"/>', f'<scale value="{s * 0.5:.3f}"/>')
    if volumes and k in ('sphere', 'cube') and r.random() < 0.6:
        med = f'<medium type="homogeneous" name="interior"><rgb name="albedo" value="{rgb(r, 0.3, 0.95)}"/><float name="sigma_t" value="{r.uniform(0.5, 5):.2f}"/><phase type="hg"><float name="g" value="{r.uniform(-0.7, 0.7):.2f}"/></phase></medium>'
        b = r.choice(['<bsdf type="null"/>', f'<bsdf type="dielectric"><float name="int_ior" value="{r.uniform(1.1, 1.6):.2f}"/></bsdf>'])
        return f'<shape type="{k}">{t}{b}{med}</shape>'
    return f'<shape type="{k}">{extra}{t}{bsdf(r)}</shape>'

def spot(r, textured):
    texture = f'<texture type="bitmap" name="texture"><string name="filename" value="{ASSETS}/tiles.png"/></texture>'
    return (f'<emitter type="spot"><transform name="to_world"><lookat origin="{r.uniform(-1,1):.2f}, 2.5, 2" '
            f'target="0,0,0"/></transform><rgb name="intensity" value="{rgb(r, 5, 20)}"/>'
            f'<float name="cutoff_angle" value="{r.uniform(15,40):.1f}"/>{texture if textured else ""}</emitter>')


def area_rectangle(r, textured):
    radiance = (f'<texture type="bitmap" name="radiance"><string name="filename" value="{ASSETS}/tiles.png"/></texture>'
                if textured else f'<rgb name="radiance" value="{rgb(r, 2, 8)}"/>')
    return (f'<shape type="rectangle"><transform name="to_world"><scale value="{r.uniform(0.2,0.8):.2f}"/>'
            f'<lookat origin="{r.uniform(-1,1):.2f}, 2, {r.uniform(0,2):.2f}" target="0,0,0"/></transform>'
            f'<emitter type="area">{radiance}</emitter></shape>')


def light(r, kind, integ):
    if kind in ('spot', 'spot_tex'):
        return spot(r, kind == 'spot_tex')
    if kind in ('area', 'area_tex'):
        return area_rectangle(r, kind == 'area_tex')
    if kind == 'point':
        return (f'<emitter type="point"><point name="position" x="{r.uniform(-1,1):.2f}" y="2" z="{r.uniform(0,2):.2f}"/>'
                f'<rgb name="intensity" value="{rgb(r, 2, 10)}"/></emitter>')
    if kind == 'area_sphere':
        return (f'<shape type="sphere"><float name="radius" value="{r.uniform(0.05,0.3):.2f}"/><point name="center" '
                f'x="{r.uniform(-1,1):.2f}" y="1.8" z="{r.uniform(0,2):.2f}"/><emitter type="area">'
                f'<rgb name="radiance" value="{rgb(r, 2, 10)}"/></emitter></shape>')
    if kind == 'sunsky':
        return (f'<emitter type="sunsky"><vector name="sun_direction" x="{r.uniform(-1,1):.2f}" y="{r.uniform(0.2,1):.2f}" '
                f'z="{r.uniform(-1,1):.2f}"/><float name="turbidity" value="{r.uniform(2,8):.1f}"/>'
                f'<transform name="to_world"><rotate x="1" angle="-90"/></transform></emitter>')
    if kind == 'constant':
        return f'<emitter type="constant"><rgb name="radiance" value="{rgb(r, 0.2, 1)}"/></emitter>'
    if kind == 'directional':
        return (f'<emitter type="directional"><vector name="direction" x="{r.uniform(-1,1):.2f}" y="-1" '
                f'z="{r.uniform(-1,0):.2f}"/><rgb name="irradiance" value="{rgb(r, 1, 4)}"/></emitter>')
    # envmap; Mitsuba 3.9.1's ptracer mishandles a rotated one (see the module notes).
    rot = '' if integ == 'ptracer' else f'<transform name="to_world"><rotate y="1" angle="{r.uniform(0,360):.0f}"/></transform>'
    return (f'<emitter type="envmap"><string name="filename" value="{ASSETS}/sky.exr"/>'
            f'<float name="scale" value="{r.uniform(0.3,1.5):.2f}"/>{rot}</emitter>')


def lights(r, integ):
    kinds = ['point', 'spot', 'area', 'constant', 'directional', 'envmap', 'area_sphere', 'spot_tex', 'sunsky', 'area_tex']
    out = [light(r, r.choice(kinds), integ) for _ in range(r.randint(1, 2))]
    # Mitsuba allows one environment emitter.
    envs = [l for l in out if 'type="constant"' in l or 'type="envmap"' in l or 'type="sunsky"' in l]
    if len(envs) > 1:
        out.remove(envs[1])
    return ''.join(out)

def sensor(r):
    k = r.choice(['perspective', 'perspective', 'thinlens', 'orthographic'])
    if k == 'thinlens':
        return f'<sensor type="thinlens"><float name="fov" value="45"/><float name="aperture_radius" value="{r.uniform(0.01,0.2):.3f}"/><float name="focus_distance" value="{r.uniform(3,6):.2f}"/>'
    if k == 'orthographic':
        return '<sensor type="orthographic">'
    return '<sensor type="perspective"><float name="fov" value="45"/>'

def rfilter(r):
    return r.choice(['<rfilter type="box"/>', '<rfilter type="gaussian"/>', '<rfilter type="tent"/>', ''])

def scene(r):
    integ = r.choice(['path', 'path', 'path', 'direct', 'volpath', 'ptracer'])
    if integ == 'direct':
        it = f'<integrator type="direct"><integer name="emitter_samples" value="1"/><integer name="bsdf_samples" value="{r.randint(1,3)}"/></integrator>'
    elif integ == 'ptracer':
        it = f'<integrator type="ptracer"><integer name="max_depth" value="{r.randint(2,6)}"/></integrator>'
    else:
        it = f'<integrator type="{integ}"><integer name="max_depth" value="{r.randint(2,8)}"/><boolean name="hide_emitters" value="{r.choice(["true","false"])}"/></integrator>'
    shapes = ''.join(shape(r, i, integ == 'volpath') for i in range(r.randint(1, 4)))
    floor = f'<shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/><translate y="-0.8"/></transform>{bsdf(r)}</shape>'
    return f'''<scene version="3.0.0">{it}
{sensor(r)}<transform name="to_world"><lookat origin="0, 1, 4.5" target="0, 0, 0" up="0, 1, 0"/></transform>
<film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>{rfilter(r)}</film>
<sampler type="independent"><integer name="sample_count" value="64"/></sampler></sensor>
{lights(r, integ)}{shapes}{floor}</scene>'''


def render_mitsuba(path, spp, seed):
    return np.array(mi.render(mi.load_file(path), spp=spp, seed=seed))[..., :3]


def render_neumann(path, spp, seed):
    out = path[:-4] + f"_n{seed}.exr"
    cmd = [NEUMANN, "render", path, "-o", out, "--spp", str(spp), "--seed", str(seed), "--quiet"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return p.stderr.strip()[-400:]
    return np.array(mi.Bitmap(out))[..., :3]


def main():
    parser = argparse.ArgumentParser(description="random scenes, Mitsuba 3 against neumann")
    parser.add_argument("--first", type=int, default=0, help="first scene number (its seed)")
    parser.add_argument("--count", type=int, default=20, help="scenes to render")
    parser.add_argument("--spp", type=int, default=128, help="samples per pixel of each render")
    parser.add_argument("--keep", help="folder to write the scenes to (default: a temporary one)")
    opts = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = opts.keep or tmp
        os.makedirs(folder, exist_ok=True)
        flagged = 0
        for k in range(opts.first, opts.first + opts.count):
            path = os.path.join(folder, f"s{k}.xml")
            with open(path, "w") as f:
                f.write(scene(random.Random(k)))
            try:
                m = [render_mitsuba(path, opts.spp, s) for s in (1, 2)]
            except Exception as e:  # Mitsuba refuses some combinations (ptracer + orthographic)
                print(f"{k}: Mitsuba refuses it: {str(e)[:160]}", flush=True)
                continue
            n = [render_neumann(path, opts.spp, s) for s in (1, 2)]
            if isinstance(n[0], str):
                print(f"{k}: neumann refuses it: {n[0]}", flush=True)
                continue
            mm, nm = np.mean([x.mean() for x in m]), np.mean([x.mean() for x in n])
            spread = (abs(m[0].mean() - m[1].mean()) + abs(n[0].mean() - n[1].mean())) / 2 + 1e-6
            bad = abs(nm - mm) > max(4 * spread, 0.01 * mm) and mm > 1e-3
            flagged += bad
            print(f"{k}: Mitsuba {mm:.5f} neumann {nm:.5f} rel {(nm - mm) / max(mm, 1e-4):+.4f} "
                  f"spread {spread / max(mm, 1e-4):.4f}{'  MISMATCH' if bad else ''}", flush=True)
        print(f"{flagged} of {opts.count} flagged")
        return 1 if flagged else 0


if __name__ == "__main__":
    sys.exit(main())
