"""Adaptive sampling against uniform sampling at equal time on the validation scenes.

For each scene: neumann renders it for SECONDS with and without --noise-threshold T, for two
seeds, at the reference's resolution; relMSE against the committed Mitsuba reference
(references/<scene>.exr) times the render's own time (so that an adaptive render that ends
early is credited), adaptive ÷ uniform, seeds averaged. Prints one table row per scene.

Run from the repository root after `cargo build --release` (Mitsuba's Python package reads the
references' EXR files):
    ~/mitsuba-venv/bin/python tools/mitsuba/adaptive.py [--threshold T] [--seconds S] [scene ...]"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
sys.path.insert(0, os.path.dirname(__file__))


def read_pfm(path):
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4").reshape(h, w, 3)
    return np.flipud(data)


def render(scene, res, seconds, seed, extra, out):
    cmd = ["target/release/neumann", "render", f"scenes/{scene}.xml", "--time", str(seconds), "--seed", str(seed),
           f"-Dres={res}", "-o", out] + extra
    said = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    elapsed = float(re.search(r", ([0-9.]+) s, ", said).group(1))
    return read_pfm(out), elapsed


def main():
    parser = argparse.ArgumentParser(description="adaptive against uniform sampling at equal time")
    parser.add_argument("--threshold", type=float, default=0.01, help="noise threshold T (Cycles' meaning)")
    parser.add_argument("--seconds", type=float, default=3.0, help="time budget of every render")
    parser.add_argument("scenes", nargs="*", help="scene names (default: all)")
    opts = parser.parse_args()
    threshold, seconds, args = opts.threshold, opts.seconds, opts.scenes
    from references import SCENES, relmse

    names = args or sorted(SCENES)
    print(f"T = {threshold}, {seconds} s per render, seeds 3 and 4")
    print("| scene | uniform relMSE | adaptive relMSE | relMSE × time, adaptive ÷ uniform |")
    print("|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.pfm")
        for name in names:
            ref = np.array(mi.Bitmap(f"references/{name}.exr"), dtype=np.float32)[:, :, :3]
            res = ref.shape[1]
            rows = {"uniform": [], "adaptive": []}
            for seed in (3, 4):
                for kind, extra in (("uniform", []), ("adaptive", ["--noise-threshold", str(threshold)])):
                    img, t = render(name, res, seconds, seed, extra, out)
                    rows[kind].append((relmse(img, ref), t))
            u = np.mean([e for e, _ in rows["uniform"]])
            a = np.mean([e for e, _ in rows["adaptive"]])
            ratio = np.mean([ea * ta / (eu * tu) for (ea, ta), (eu, tu) in zip(rows["adaptive"], rows["uniform"])])
            print(f"| {name} | {u:.4g} | {a:.4g} | {ratio:.2f} |", flush=True)


if __name__ == "__main__":
    main()
