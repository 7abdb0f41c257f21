#!/usr/bin/env python3
"""Denoises a rendered scene folder and prints its quality against the reference.

    scripts/quickstart.sh          # renders out/quickstart/scene (with reference/)
    PYTHONPATH=build/release/python python3 examples/python/denoise_scene.py \\
        [SCENE_DIR] [--method svgf] [--device cpu] [--out DIR] [any --setting value]
"""
import argparse
import os

import rtdenoise

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
parser.add_argument("scene", nargs="?", default="out/quickstart/scene")
parser.add_argument("--method", default="detail", help="jbf, atrous, temporal, svgf, detail")
parser.add_argument("--device", default="default", help="default, cpu, cuda")
parser.add_argument("--out", help="also write result_<i>.exr into this folder")
args, extra = parser.parse_known_args()
# The remaining "--sigma-color 0.8" pairs are settings, as the command line takes them.
number = lambda text: int(text) if text.lstrip("-").isdigit() else float(text)
settings = {name.lstrip("-"): number(value) for name, value in zip(extra[::2], extra[1::2])}

den = rtdenoise.Denoiser(args.method, device=args.device, **settings)
frames = rtdenoise.open_sequence(args.scene)
print(f"{frames.description}: {args.method} on {den.device_name}")
results = []
for i, frame in enumerate(frames):
    results.append(den.denoise_frame(frame))
    if args.out:
        os.makedirs(args.out, exist_ok=True)
        rtdenoise.write_exr(os.path.join(args.out, f"result_{i}.exr"), results[-1])

comparison = rtdenoise.compare(results, os.path.join(args.scene, "reference"))
print(comparison.table(), end="")
print(f"mean relMSE {comparison.mean.relmse:.4f}, PSNR {comparison.mean.psnr:.2f} dB")
