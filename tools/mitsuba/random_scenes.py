"""Differential testing against Mitsuba 3: random small scenes rendered by both, compared by
their means and by 4 × 4 regions of the image.

Each scene (seeded, so reproducible by its number) has 1–4 random shapes over a floor (sphere by
transform or by centre and radius, rectangle, cube, disk, cylinder, the knot as OBJ, PLY and
serialized meshes with or without face normals, flipped normals, shape groups instanced once or
twice), random BSDFs of 18 kinds (nested blends, masks, two-sided, normal and bump maps, textured
parameters), 1–2 random lights of 10 kinds (point, spot and textured spot with or without a beam
width, area rectangle, textured area, area sphere, directional, constant, envmap, sunsky), a
random integrator (path, direct, volpath and volpathmis with homogeneous or grid media inside
spheres and cubes, ptracer; `rr_depth` sometimes low), sensor (perspective with `fov` on any
`fov_axis` or a `focal_length`, principal-point shifts, thin lens, orthographic; `near_clip`),
film (non-square, crop windows), filter and sampler. Mitsuba (`scalar_rgb`, in a process of its
own: it crashes on some scenes) and neumann render it at the same spp with four seeds each; a
scene is flagged MISMATCH when the means, or one region's, differ by more than 5 standard errors
(from the seeds) and 1 % (3 % for a region). A flagged scene is then bisected by hand (drop one
element at a time) down to an analytic case: the differences found so far were neumann's (fixed)
or Mitsuba 3.9.1's own, listed in the README ("Mitsuba 3 scenes"), which this generator avoids:
fractional `mask` opacity under `path`, `blendbsdf` of a delta and a smooth lobe, `direct` with
several emitter samples and a delta light, `ptracer` under a rotated envmap, non-unit rotation
axes, `hide_emitters` with instances (Mitsuba crashes), `ptracer` with a principal-point shift, anisotropic roughness under bump maps. Known and not avoided: Mitsuba 3.9.1's `ldsampler` is biased in some scenes (a flagged `ldsampler` scene is re-run with `independent` before bisecting); its light sampling misses an occluder crossing an emitting rectangle (two random rectangle lights that cross); its `principledthin`
with `diff_trans` under two lights renders up to 1 % darker than the sum of its images under each; under
`hide_emitters` it lights too brightly a surface seen through an emitting shape that lights it (a flagged
`hide_emitters` scene is re-run with it off before bisecting); its `ptracer` with a crop window drops the light
paths landing outside the window, whose filter weight neumann's edge pixels keep (a flagged `ptracer` scene
with a crop window is re-run without it). Its `ptracer` also renders black the surfaces of two `roughconductor`s
whose `alpha` textures read the same image (a flagged `ptracer` scene with two such is re-run with one `alpha`
constant). `ptracer` scenes are noisy (caustics
through the BSDFs' delta lobes): re-run a flagged one at more spp before bisecting it. In
particular Mitsuba's `ptracer` reaches a directly visible `envmap` or `sunsky` only through
sparse splats (its visible-emitter step samples directions by the emitter's radiance, from the
camera's position, and splats where they land: at 64 spp 3-7 % of the sky's pixels receive
one), a heavy-tailed estimate that four seeds can show black in a whole region or several
per cent low in 4096 spp, where neumann's `ptracer` looks the environment up along escaping
camera rays (as its and Mitsuba's `path` do, with which it agrees).

Run from the repository root after `cargo build --release`, with Mitsuba in a venv outside it:
    ~/mitsuba-venv/bin/python tools/mitsuba/random_scenes.py [--first N] [--count K] [--spp S] [--keep DIR]
(--keep writes each scene there as sK.xml for bisecting; default a temporary folder.)"""
import argparse
import os
import random
import re
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
# Seconds either renderer may take for one scene (a neumann render that takes longer is flagged).
TIMEOUT = 180


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
    return bitmap(r, name)


def bitmap(r, name):
    """The tiles image with random lookup settings: filter, wrap mode, a to_uv placement."""
    extra = ''
    if r.random() < 0.5:
        extra += f'<string name="filter_type" value="{r.choice(["bilinear", "nearest"])}"/>'
        extra += f'<string name="wrap_mode" value="{r.choice(["repeat", "mirror", "clamp"])}"/>'
    if r.random() < 0.5:
        extra += (f'<transform name="to_uv"><scale x="{r.uniform(0.5, 3):.2f}" y="{r.uniform(0.5, 3):.2f}"/>'
                  f'<rotate z="1" angle="{r.uniform(0, 90):.0f}"/><translate x="{r.uniform(-0.5, 0.5):.2f}" '
                  f'y="{r.uniform(-0.5, 0.5):.2f}"/></transform>')
    return f'<texture type="bitmap" name="{name}"><string name="filename" value="{ASSETS}/tiles.png"/>{extra}</texture>'


def bsdf(r, depth=0, perturbed=False):
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
        if perturbed:  # Mitsuba 3.9.1 orients anisotropy under a bump map by the world tangent
            an = f'<float name="alpha" value="{alpha:.3f}"/>'
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
        return f'<bsdf type="bumpmap"><texture type="bitmap"><string name="filename" value="{ASSETS}/tiles.png"/><boolean name="raw" value="true"/></texture><float name="scale" value="{r.uniform(0.1, 2):.2f}"/>{bsdf(r, 2, True)}</bsdf>'
    if k == 'texrough':
        return f'<bsdf type="roughconductor">{dist}<texture type="bitmap" name="alpha"><string name="filename" value="{ASSETS}/tiles.png"/></texture><string name="material" value="{r.choice(["Au","Cu","Al"])}"/></bsdf>'

def bsdf_diffuse(r):
    return f'<bsdf type="diffuse">{tex(r, "reflectance")}</bsdf>'

def shape(r, i, volumes=False):
    k = r.choice(['sphere', 'rectangle', 'cube', 'disk', 'cylinder', 'obj', 'ply', 'serialized', 'sphere_c', 'instance'])
    if k == 'instance':
        return instance(r, i)
    if k == 'sphere_c':
        # A sphere by centre and radius (no to_world), as exporters write it.
        flip = '<boolean name="flip_normals" value="true"/>' if r.random() < 0.2 else ''
        return (f'<shape type="sphere"><point name="center" x="{r.uniform(-1,1):.2f}" y="{r.uniform(-0.5,0.6):.2f}" '
                f'z="{r.uniform(-1,0.5):.2f}"/><float name="radius" value="{r.uniform(0.2,0.6):.2f}"/>{flip}{bsdf(r)}</shape>')
    s = r.uniform(0.3, 0.8)
    ax = np.array([r.random(), r.random(), r.random()]) + 1e-3; ax /= np.linalg.norm(ax)
    t = f'<transform name="to_world"><scale value="{s:.3f}"/><rotate x="{ax[0]:.6f}" y="{ax[1]:.6f}" z="{ax[2]:.6f}" angle="{r.uniform(0,360):.1f}"/><translate x="{r.uniform(-1,1):.2f}" y="{r.uniform(-0.6,0.8):.2f}" z="{r.uniform(-1,0.5):.2f}"/></transform>'
    files = {'obj': 'knot.obj', 'ply': 'knot_colors.ply', 'serialized': 'knot.serialized'}
    extra = f'<string name="filename" value="{ASSETS}/{files[k]}"/>' if k in files else ''
    if k in files and r.random() < 0.3:
        extra += '<boolean name="face_normals" value="true"/>'
    if k in ('obj', 'ply', 'serialized', 'cylinder', 'disk', 'rectangle') and r.random() < 0.15:
        extra += '<boolean name="flip_normals" value="true"/>'
    if k in files:
        t = t.replace(f'<scale value="{s:.3f}"/>', f'<scale value="{s * 0.5:.3f}"/>')
    if volumes and k in ('sphere', 'cube') and r.random() < 0.6:
        phase = f'<phase type="hg"><float name="g" value="{r.uniform(-0.7, 0.7):.2f}"/></phase>' if r.random() < 0.7 else ''
        if r.random() < 0.7:
            med = f'<medium type="homogeneous" name="interior"><rgb name="albedo" value="{rgb(r, 0.3, 0.95)}"/><float name="sigma_t" value="{r.uniform(0.5, 5):.2f}"/>{phase}</medium>'
        else:
            # A grid over the shape's box (the unit cube moved as the shape: [-1, 1]³ scaled).
            grid = (f'<volume type="gridvolume" name="sigma_t"><string name="filename" value="{ASSETS}/smoke.vol"/>'
                    f'<transform name="to_world">{t[t.index(">") + 1:t.rindex("<")]}</transform></volume>')
            grid = grid.replace('<transform name="to_world"><scale', '<transform name="to_world"><translate value="-0.5"/><scale value="2"/><scale', 1)
            med = (f'<medium type="heterogeneous" name="interior"><rgb name="albedo" value="{rgb(r, 0.3, 0.95)}"/>'
                   f'{grid}<float name="scale" value="{r.uniform(1, 8):.2f}"/>{phase}</medium>')
        b = r.choice(['<bsdf type="null"/>', f'<bsdf type="dielectric"><float name="int_ior" value="{r.uniform(1.1, 1.6):.2f}"/></bsdf>'])
        return f'<shape type="{k}">{t}{b}{med}</shape>'
    return f'<shape type="{k}">{extra}{t}{bsdf(r)}</shape>'

def instance(r, i):
    """A shape group of one or two shapes, instanced once or twice with their own transforms."""
    members = ''.join(shape(r, i).replace('<shape type="shapegroup"', '<shape type="x"') for _ in range(r.randint(1, 2)))
    members = members if 'type="instance"' not in members else shape_simple(r)
    out = f'<shape type="shapegroup" id="group{i}">{members}</shape>'
    for _ in range(r.randint(1, 2)):
        out += (f'<shape type="instance"><ref id="group{i}"/><transform name="to_world"><scale value="{r.uniform(0.5, 1.2):.2f}"/>'
                f'<rotate y="1" angle="{r.uniform(0, 360):.0f}"/><translate x="{r.uniform(-0.8, 0.8):.2f}" '
                f'z="{r.uniform(-0.8, 0.3):.2f}"/></transform></shape>')
    return out


def shape_simple(r):
    return (f'<shape type="cube"><transform name="to_world"><scale value="{r.uniform(0.2, 0.5):.2f}"/></transform>'
            f'{bsdf(r)}</shape>')


def spot(r, textured):
    texture = f'<texture type="bitmap" name="texture"><string name="filename" value="{ASSETS}/tiles.png"/></texture>'
    beam = f'<float name="beam_width" value="{r.uniform(5, 14):.1f}"/>' if r.random() < 0.5 else ''
    return (f'<emitter type="spot"><transform name="to_world"><lookat origin="{r.uniform(-1,1):.2f}, 2.5, 2" '
            f'target="0,0,0"/></transform><rgb name="intensity" value="{rgb(r, 5, 20)}"/>'
            f'<float name="cutoff_angle" value="{r.uniform(15,40):.1f}"/>'
            f'{beam}{texture if textured else ""}</emitter>')


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

def field_of_view(r):
    if r.random() < 0.3:
        return f'<string name="focal_length" value="{r.choice([28, 35, 50, 70])}mm"/>'
    axis = r.choice(['x', 'y', 'diagonal', 'smaller', 'larger'])
    return f'<float name="fov" value="{r.uniform(30, 60):.1f}"/><string name="fov_axis" value="{axis}"/>'


def sensor(r):
    k = r.choice(['perspective', 'perspective', 'thinlens', 'orthographic'])
    clip = f'<float name="near_clip" value="{r.uniform(0.01, 3):.2f}"/>' if r.random() < 0.2 else ''
    if k == 'thinlens':
        return f'<sensor type="thinlens">{field_of_view(r)}{clip}<float name="aperture_radius" value="{r.uniform(0.01,0.2):.3f}"/><float name="focus_distance" value="{r.uniform(3,6):.2f}"/>'
    if k == 'orthographic':
        return f'<sensor type="orthographic">{clip}'
    shift = ''
    if r.random() < 0.3:
        shift = (f'<float name="principal_point_offset_x" value="{r.uniform(-0.3, 0.3):.2f}"/>'
                 f'<float name="principal_point_offset_y" value="{r.uniform(-0.3, 0.3):.2f}"/>')
    return f'<sensor type="perspective">{field_of_view(r)}{clip}{shift}'


def without_shift(sensor_xml):
    """The sensor without its principal-point shift (Mitsuba 3.9.1's ptracer ignores it)."""
    return re.sub(r'<float name="principal_point_offset_[xy]" value="[-0-9.]*"/>', '', sensor_xml)


def film(r):
    w, h = r.choice([(32, 32), (48, 24), (24, 40), (40, 32)])
    crop = ''
    if r.random() < 0.2:
        cw, ch = r.randint(8, w), r.randint(8, h)
        crop = (f'<integer name="crop_offset_x" value="{r.randint(0, w - cw)}"/><integer name="crop_offset_y" '
                f'value="{r.randint(0, h - ch)}"/><integer name="crop_width" value="{cw}"/><integer name="crop_height" value="{ch}"/>')
    return f'<film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>{crop}{rfilter(r)}</film>'

def rfilter(r):
    return r.choice(['<rfilter type="box"/>', '<rfilter type="gaussian"/>', '<rfilter type="tent"/>', ''])

def scene(r):
    integ = r.choice(['path', 'path', 'path', 'direct', 'volpath', 'volpathmis', 'ptracer'])
    if integ == 'direct':
        it = f'<integrator type="direct"><integer name="emitter_samples" value="1"/><integer name="bsdf_samples" value="{r.randint(1,3)}"/></integrator>'
    elif integ == 'ptracer':
        it = f'<integrator type="ptracer"><integer name="max_depth" value="{r.randint(2,6)}"/></integrator>'
    else:
        rr = f'<integer name="rr_depth" value="{r.randint(1, 4)}"/>' if r.random() < 0.3 else ''
        it = f'<integrator type="{integ}"><integer name="max_depth" value="{r.randint(2,8)}"/>{rr}<boolean name="hide_emitters" value="{r.choice(["true","false"])}"/></integrator>'
    shapes = ''.join(shape(r, i, integ.startswith('volpath')) for i in range(r.randint(1, 4)))
    if 'type="instance"' in shapes:
        # Mitsuba 3.9.1 (scalar_rgb) crashes on camera rays that hit an instance under hide_emitters.
        it = it.replace('name="hide_emitters" value="true"', 'name="hide_emitters" value="false"')
    floor = f'<shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/><translate y="-0.8"/></transform>{bsdf(r)}</shape>'
    return f'''<scene version="3.0.0">{it}
{sensor(r) if integ != 'ptracer' else without_shift(sensor(r))}<transform name="to_world"><lookat origin="0, 1, 4.5" target="0, 0, 0" up="0, 1, 0"/></transform>
{film(r)}
<sampler type="{r.choice(['independent', 'independent', 'stratified', 'multijitter', 'ldsampler'])}"><integer name="sample_count" value="64"/></sampler></sensor>
{lights(r, integ)}{shapes}{floor}</scene>'''


MITSUBA_RENDER = '''
import sys, numpy as np, mitsuba as mi
mi.set_variant("scalar_rgb")
mi.set_log_level(mi.LogLevel.Error)
path, spp, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
scene = mi.load_file(path)
np.save(out, np.stack([np.array(mi.render(scene, spp=spp, seed=seed))[..., :3] for seed in (1, 2, 3, 4)]))
'''


def render_mitsuba(path, spp):
    """Mitsuba's four renders (seeds 1 to 4), in a process of their own: Mitsuba 3.9.1 crashes on
    some scenes (a segmentation fault), which must not end the run."""
    out = path[:-4] + "_m.npy"
    try:
        p = subprocess.run([sys.executable, "-c", MITSUBA_RENDER, path, str(spp), out], capture_output=True,
                           text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        # Mitsuba 3.9.1 hangs on some scenes (a ptracer scene of 48 × 24 pixels ran for minutes).
        raise RuntimeError(f"no image after {TIMEOUT} s")
    if p.returncode != 0:
        raise RuntimeError(p.stderr.strip()[-160:] or f"exit status {p.returncode}")
    return list(np.load(out))


def render_neumann(path, spp, seed):
    out = path[:-4] + f"_n{seed}.exr"
    cmd = [NEUMANN, "render", path, "-o", out, "--spp", str(spp), "--seed", str(seed), "--quiet"]
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return f"HANG: no image after {TIMEOUT} s"
    if p.returncode != 0:
        return p.stderr.strip()[-400:]
    return np.array(mi.Bitmap(out))[..., :3]


def standard_error(a, b):
    """Standard error of mean(b) − mean(a), from the spread of each renderer's seeds."""
    return np.sqrt(np.var(a, ddof=1) / len(a) + np.var(b, ddof=1) / len(b))


def regions(m, n, image_mean, grid=4):
    """The worst of grid × grid regions: (score, (row, col), relative difference), the score
    above 1 where the region's means differ by more than 5 standard errors (from the seeds) and
    3 % (of the region's mean, or 1 % of the image's); None for an empty image."""
    if image_mean <= 1e-3:
        return None
    h, w = m[0].shape[:2]
    worst = (0.0, None, 0.0)
    for i in range(grid):
        for j in range(grid):
            rows, cols = slice(i * h // grid, (i + 1) * h // grid), slice(j * w // grid, (j + 1) * w // grid)
            a = [x[rows, cols].mean() for x in m]
            b = [x[rows, cols].mean() for x in n]
            ma, mb = np.mean(a), np.mean(b)
            allowed = max(5 * standard_error(a, b), 0.03 * ma, 0.01 * image_mean)
            score = abs(mb - ma) / allowed
            if score > worst[0]:
                worst = (score, (i, j), (mb - ma) / max(ma, 1e-4))
    return worst


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
                m = render_mitsuba(path, opts.spp)
            except Exception as e:  # Mitsuba refuses some combinations (ptracer + orthographic)
                print(f"{k}: Mitsuba refuses it: {str(e)[:160]}", flush=True)
                continue
            n = [render_neumann(path, opts.spp, s) for s in (1, 2, 3, 4)]
            if any(isinstance(x, str) for x in n):
                refusal = next(x for x in n if isinstance(x, str))
                hang = refusal.startswith("HANG")
                flagged += hang
                print(f"{k}: neumann refuses it: {refusal}{'  MISMATCH' if hang else ''}", flush=True)
                continue
            if m[0].shape != n[0].shape:
                flagged += 1
                print(f"{k}: image sizes differ: Mitsuba {m[0].shape}, neumann {n[0].shape}  MISMATCH", flush=True)
                continue
            mm, nm = np.mean([x.mean() for x in m]), np.mean([x.mean() for x in n])
            spread = standard_error([x.mean() for x in m], [x.mean() for x in n]) + 1e-6
            bad = abs(nm - mm) > max(5 * spread, 0.01 * mm) and mm > 1e-3
            # The same test on each of 4 × 4 regions of the image (a wrong placement, a light
            # or texture mapped elsewhere, can keep the whole image's mean).
            worst = regions(m, n, mm)
            region_bad = worst is not None and worst[0] > 1
            flagged += bad or region_bad
            where = f" region {worst[1]} off by {worst[2]:+.3f}" if region_bad else ""
            print(f"{k}: Mitsuba {mm:.5f} neumann {nm:.5f} rel {(nm - mm) / max(mm, 1e-4):+.4f} "
                  f"spread {spread / max(mm, 1e-4):.4f}{where}{'  MISMATCH' if bad or region_bad else ''}", flush=True)
        print(f"{flagged} of {opts.count} flagged")
        return 1 if flagged else 0


if __name__ == "__main__":
    sys.exit(main())
