"""How much any adaptive sampler could gain on a scene: bounds from the per-pixel variance.

For relMSE (the mean over pixels of (img - ref)^2 / (ref^2 + 1e-2)), a pixel i with per-sample
relative variance v_i that takes n_i samples contributes v_i / n_i. Uniform sampling (n_i = N)
gives mean(v) / N; at the same total budget the best allocation is n_i proportional to sqrt(v_i),
which gives mean(sqrt v)^2 / N (Cauchy-Schwarz). A stopping rule of Cycles' kind (a pixel stops
once its error is below a threshold) equalises the error of the pixels it stops instead: n_i
proportional to v_i, the rest sharing what is left of the budget.

v_i is measured, not known: neumann renders the scene twice (two seeds, --aov variance, SPP
samples). Allocating from one map and scoring on the other (independent) one gives what an
allocation informed by a SPP-sample pilot render would achieve; allocating and scoring on the
same map is optimistic (it "knows" where the fireflies of that very render fell). Printed per
scene, as ratios to uniform sampling:
    self      sqrt-allocation scored on its own map (a lower bound, too optimistic)
    pilot     sqrt-allocation from the other map
    pilot5    the same, with the pilot's map averaged over 5x5 pixels first (the best found)
    rule5     the best stopping rule (threshold searched) informed by that smoothed pilot
              map, with --min-spp MIN samples and a uniform budget of N samples per pixel
    cycles5   the same with Cycles' error measure (noise relative to sqrt of brightness)

Run from the repository root after `cargo build --release`:
    ~/mitsuba-venv/bin/python tools/mitsuba/adaptive_bound.py [--spp 4096] [--budget 512] [scene ...]"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import mitsuba as mi

mi.set_variant("scalar_rgb")
sys.path.insert(0, os.path.dirname(__file__))


def variance_map(scene, res, spp, seed, ref, out):
    """Per-pixel, per-sample relative variance of one neumann render (summed over channels)."""
    subprocess.run(["target/release/neumann", "render", f"scenes/{scene}.xml", "--spp", str(spp), "--seed", str(seed),
                    f"-Dres={res}", "--aov", "variance", "-o", out], check=True, capture_output=True)
    layers = dict(mi.Bitmap(out).split())
    var = np.array(layers["variance"], dtype=np.float64) * spp
    # Cycles' error measure (noise relative to the square root of brightness), squared.
    cycles = var.sum(axis=2) / (1e-4 + np.maximum(ref.sum(axis=2), 0.0))
    return (var / (ref ** 2 + 1e-2)).sum(axis=2), cycles


def box(v, k):
    pad = np.pad(v, k // 2, mode="edge")
    h, w = v.shape
    return sum(pad[i:i + h, j:j + w] for i in range(k) for j in range(k)) / (k * k)


def sqrt_ratio(alloc_from, scored_on):
    n = np.sqrt(alloc_from)
    n = n + 1e-3 * n.mean()  # a pixel the pilot saw no noise in still takes some samples
    n = n / n.mean()
    return (scored_on / np.maximum(n, 1e-12)).mean() / scored_on.mean()


def rule_ratio(alloc_from, scored_on, budget, min_spp):
    """The best threshold of a stopping rule that stops pixel i after max(min_spp, e_i / tau^2)
    samples, pixels that cannot stop sharing the rest of the budget equally."""
    e = alloc_from.ravel()
    v = scored_on.ravel()
    total = budget * e.size
    best = np.inf
    for tau2 in np.geomspace(max(e.max(), 1e-30) * 1e-7, max(e.max(), 1e-30), 300):
        need = np.maximum(e / tau2, min_spp)
        order = np.argsort(need)
        sorted_need = need[order]
        spent = np.concatenate([[0.0], np.cumsum(sorted_need)])
        left = e.size - np.arange(e.size)
        share = (total - spent[:-1]) / left
        stop = np.nonzero(share < sorted_need)[0]
        k = stop[0] if stop.size else e.size
        alloc = np.empty_like(e)
        alloc[order[:k]] = sorted_need[:k]
        if k < e.size:
            alloc[order[k:]] = (total - spent[k]) / (e.size - k)
        best = min(best, (v / alloc).mean() / (v.mean() / budget))
    return best


def main():
    parser = argparse.ArgumentParser(description="bounds on adaptive sampling's gain per scene")
    parser.add_argument("--spp", type=int, default=4096, help="samples per pixel of each variance render")
    parser.add_argument("--budget", type=float, default=512, help="uniform samples per pixel at equal time")
    parser.add_argument("--min-spp", type=float, default=64, help="the stopping rule's minimum")
    parser.add_argument("scenes", nargs="*", help="scene names (default: all)")
    opts = parser.parse_args()
    from references import SCENES

    print(f"relMSE ratios to uniform sampling; variance from 2 x {opts.spp} spp, budget {opts.budget} spp")
    print("| scene | self | pilot | pilot5 | rule5 | cycles5 |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.exr")
        for name in opts.scenes or sorted(SCENES):
            ref = np.array(mi.Bitmap(f"references/{name}.exr"), dtype=np.float64)[:, :, :3]
            res = ref.shape[1]
            a, ca = variance_map(name, res, opts.spp, 11, ref, out)
            b, cb = variance_map(name, res, opts.spp, 12, ref, out)
            mean = lambda f: 0.5 * (f(a, b) + f(b, a))
            cols = [
                mean(lambda x, y: sqrt_ratio(y, y)),
                mean(sqrt_ratio),
                mean(lambda x, y: sqrt_ratio(box(x, 5), y)),
                mean(lambda x, y: rule_ratio(box(x, 5), y, opts.budget, opts.min_spp)),
                0.5 * (rule_ratio(box(ca, 5), b, opts.budget, opts.min_spp)
                       + rule_ratio(box(cb, 5), a, opts.budget, opts.min_spp)),
            ]
            print(f"| {name} | " + " | ".join(f"{c:.2f}" for c in cols) + " |", flush=True)


if __name__ == "__main__":
    main()
