"""Times neumann and Mitsuba 3 (llvm_ad_rgb) side by side on the same scene files, in one run.

Each scene is rendered by both as whole processes (scene loading, Mitsuba's kernel compilation
from its on-disk cache after one untimed warm-up render, the render, writing the image), at the
same resolution, samples per pixel and maximum depth; the best of RUNS wall-clock times is kept
for each. Prints samples/s and neumann's ratio to Mitsuba (> 1: neumann is faster).

Run from the repository root after `cargo build --release`, with Mitsuba in a venv outside the
repository (libLLVM from the system: Debian 12's libllvm14/15 crash in Dr.Jit's AVX-512 code
generation; `apt-get install libllvm19` and point DRJIT_LIBLLVM_PATH at it):
    python3 -m venv ~/mitsuba-venv && ~/mitsuba-venv/bin/pip install mitsuba==3.9.1 numpy
    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        ~/mitsuba-venv/bin/python tools/mitsuba/speed.py [--res N] [--runs K] [scene ...]
Default scenes: the Cornell box at 512², 64 spp, max_depth 8, then every validation scene
(tools/mitsuba/references.py) at the settings `neumann validate` uses (--res, default 128).
--depths 1,2,3,8 adds the Cornell box at 512², 64 spp at each of those maximum depths: where the
ratio changes with depth tells camera rays and direct light (depth ≤ 2) from bounces.
--neumann BIN (repeatable) times these neumann binaries instead of target/release/neumann, each
in its own column with its ratio, interleaved run by run: a before and an after in one run.
--scalar also times Mitsuba's scalar_rgb variant (one path at a time per thread, as neumann
renders) and prints neumann's ratio to it: the share of the gap that is SIMD width."""
import argparse
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(__file__))

MITSUBA_ONE = """
import sys, mitsuba as mi
mi.set_variant(sys.argv[3])
mi.set_log_level(mi.LogLevel.Warn)
params = dict(a.split('=', 1) for a in sys.argv[4:])
scene = mi.load_file(sys.argv[1], **params)
mi.Bitmap(mi.render(scene, spp=int(params['spp']))).write(sys.argv[2])
"""


def timed(cmd):
    start = time.time()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.time() - start


def main():
    parser = argparse.ArgumentParser(description="neumann and Mitsuba llvm_ad_rgb side by side")
    parser.add_argument("--res", type=int, default=128, help="film size of the validation scenes")
    parser.add_argument("--runs", type=int, default=2, help="timed runs of each renderer (the best counts)")
    parser.add_argument("--depths", default="", help="also the Cornell box at these max_depth values (comma-separated)")
    parser.add_argument("--neumann", action="append", default=[],
                        help="a neumann binary to time (repeatable; default: target/release/neumann)")
    parser.add_argument("scenes", nargs="*", help="scene names (default: all)")
    parser.add_argument("--scalar", action="store_true",
                        help="also time Mitsuba's scalar_rgb variant, with neumann's (first binary's) ratio to it")
    opts = parser.parse_args()
    res, runs, args = opts.res, opts.runs, opts.scenes
    from references import SCENES

    jobs = [("cbox", 512, 64, {"max_depth": "8"})]
    jobs += [(name, res, spec[1], dict(spec[2])) for name, spec in SCENES.items()]
    if args:
        jobs = [j for j in jobs if j[0] in args]
    jobs += [("cbox", 512, 64, {"max_depth": d}) for d in opts.depths.split(",") if d]
    binaries = opts.neumann or [os.path.join("target", "release", "neumann")]
    labels = [f"neumann M/s" if len(binaries) == 1 else f"#{k + 1} M/s" for k in range(len(binaries))]
    for k, b in enumerate(binaries):
        if len(binaries) > 1:
            print(f"#{k + 1}: {b}")
    columns = "".join(f"  {label:>11}  ratio" for label in labels)
    if opts.scalar:
        columns += f"  {'scalar M/s':>11}  ratio"
    print(f"{'scene':<18} {'res':>5} {'spp':>5} {'depth':>5}  {'Mitsuba M/s':>11}{columns}")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.exr")
        for name, r, spp, extra in jobs:
            params = dict(res=str(r), spp=str(spp), **extra)
            scene = f"scenes/{name}.xml"
            n_cmds = [[b, "render", scene, "-o", out] + [f"-D{k}={v}" for k, v in params.items()] for b in binaries]
            m_args = [scene, out] + [f"{k}={v}" for k, v in params.items()]
            m_cmd = [sys.executable, "-c", MITSUBA_ONE] + m_args[:2] + ["llvm_ad_rgb"] + m_args[2:]
            s_cmd = [sys.executable, "-c", MITSUBA_ONE] + m_args[:2] + ["scalar_rgb"] + m_args[2:]
            try:
                timed(m_cmd)  # warm-up: fills Dr.Jit's kernel cache
            except subprocess.CalledProcessError:
                # Mitsuba's llvm_ad_rgb cannot render every scene (filters: a sensor filter it refuses).
                print(f"{name:<18} {r:>5} {spp:>5} {extra.get('max_depth', ''):>5}  Mitsuba llvm_ad_rgb failed on it: skipped", flush=True)
                continue
            t_n = [float("inf")] * len(binaries)
            t_m = t_s = float("inf")
            for _ in range(runs):
                for k, cmd in enumerate(n_cmds):
                    t_n[k] = min(t_n[k], timed(cmd))
                t_m = min(t_m, timed(m_cmd))
                if opts.scalar:
                    t_s = min(t_s, timed(s_cmd))
            samples = r * r * spp
            depth = extra.get("max_depth", "")
            cells = "".join(f"  {samples / t / 1e6:>11.3f}  {t_m / t:5.2f}" for t in t_n)
            if opts.scalar:
                cells += f"  {samples / t_s / 1e6:>11.3f}  {t_s / t_n[0]:5.2f}"
            print(f"{name:<18} {r:>5} {spp:>5} {depth:>5}  {samples / t_m / 1e6:>11.3f}{cells}", flush=True)


if __name__ == "__main__":
    main()
