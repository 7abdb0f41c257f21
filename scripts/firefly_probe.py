#!/usr/bin/env python3
"""One isolated firefly per frame: copies a rendered scene (rtdenoise render ... DIR), sets one
pixel's beauty to VALUE in every frame, denoises the copy with each method and prints the result
at that pixel and two pixels to its right, against the reference (docs/quality.md).
  PYTHONPATH=build/release/python scripts/firefly_probe.py DIR [VALUE=1000] [X=70 Y=60]"""
import pathlib
import shutil
import subprocess
import sys
import tempfile

import rtdenoise

scene = pathlib.Path(sys.argv[1])
value = float(sys.argv[2]) if len(sys.argv) > 2 else 1000.0
x, y = (int(sys.argv[3]), int(sys.argv[4])) if len(sys.argv) > 4 else (70, 60)
binary = pathlib.Path(__file__).resolve().parent.parent / "build/release/rtdenoise"
with tempfile.TemporaryDirectory() as work:
    noisy = pathlib.Path(work) / "scene"
    shutil.copytree(scene, noisy)
    frames = sorted(noisy.glob("beauty_*.exr"), key=lambda p: int(p.stem.split("_")[1]))
    for path in frames:
        image = rtdenoise.read_exr(path)
        image[y, x, :] = value
        rtdenoise.write_exr(path, image)
    for method in ("atrous", "temporal", "svgf", "detail"):
        out = pathlib.Path(work) / method
        subprocess.run([binary, "denoise", noisy, "-o", out, "--method", method, "-q"], check=True)
        for i in (0, len(frames) // 2, len(frames) - 1):
            result = rtdenoise.read_exr(out / f"result_{i}.exr")
            reference = rtdenoise.read_exr(noisy / "reference" / f"reference_{i}.exr")
            print(f"{method:8s} frame {i}: at the firefly {result[y, x].mean():9.3f} "
                  f"(reference {reference[y, x].mean():.3f}), two pixels right "
                  f"{result[y, x + 2].mean():7.3f}")
