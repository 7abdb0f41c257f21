#!/usr/bin/env python3
"""A prototype of an output stabilisation pass, run on results already written (docs/quality.md,
"Where thin-geometry's temporal error comes from", 2026-12-04).

Each frame's result is blended with the previous stabilised result, clamped first to the current
result's 3x3 mean +- k standard deviations (NVIDIA NRD ReBLUR's temporal stabilisation, in its
simplest form): out = current + beta * (clamp(previous) - current), where the pixel shows the same
object as in the frame before; elsewhere the current result. The previous result is taken at the
same pixel (no reprojection), so only scenes with a still camera give meaningful figures.

    scripts/stabilisation_prototype.py SCENE_DIR RESULT_DIR OUT_DIR [--beta 0.3] [--k 1.0]

SCENE_DIR: a `rtdenoise render` folder (its ID_<i>.exr); RESULT_DIR: `rtdenoise denoise`'s
result_<i>.exr; OUT_DIR receives result_<i>.exr for `rtdenoise compare`. Needs numpy and the
Python module (PYTHONPATH=build/release/python).
"""
import argparse
import os

import numpy as np
import rtdenoise


def window_mean(image: np.ndarray) -> np.ndarray:
    """The 3x3 mean of each pixel (edges repeated)."""
    padded = np.pad(image, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = image.shape[:2]
    return sum(padded[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)) / 9.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene")
    parser.add_argument("results")
    parser.add_argument("out")
    parser.add_argument("--beta", type=float, default=0.3, help="share of the previous result")
    parser.add_argument("--k", type=float, default=1.0, help="clamp half-width, standard deviations")
    a = parser.parse_args()
    os.makedirs(a.out, exist_ok=True)
    frames = 0
    while os.path.exists(os.path.join(a.results, f"result_{frames}.exr")):
        frames += 1
    previous = None
    previous_id = None
    for i in range(frames):
        current = rtdenoise.read_exr(os.path.join(a.results, f"result_{i}.exr"))
        ids = rtdenoise.read_exr(os.path.join(a.scene, f"ID_{i}.exr"))[..., 0]
        out = current
        if previous is not None:
            mean = window_mean(current)
            sigma = np.sqrt(np.maximum(window_mean(current * current) - mean * mean, 0.0))
            held = np.clip(previous, mean - a.k * sigma, mean + a.k * sigma)
            same = (ids == previous_id)[..., None]
            out = np.where(same, current + (held - current) * a.beta, current)
        out = np.ascontiguousarray(out, dtype=np.float32)
        rtdenoise.write_exr(os.path.join(a.out, f"result_{i}.exr"), out)
        previous, previous_id = out, ids


if __name__ == "__main__":
    main()
