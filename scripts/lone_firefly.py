#!/usr/bin/env python3
"""A lone firefly (issue 38, item 7; docs/quality.md): one pixel of a sequence set to 1000x the
mean of its 7x7 neighbourhood in one frame only (the first, with no history, and a later one),
denoised by every method with and without it. Prints, per method and frame, the result at that
pixel over the result without the firefly (the target: within 2x), the largest such ratio over
the 15x15 pixels around it (a blob), and the ratio at that pixel in the next frame.

  PYTHONPATH=build/release/python scripts/lone_firefly.py SEQ [--frames 0,5] [--value 1000]
                                                          [--no-energy]

SEQ: a folder with `reference/` (a generated corpus's sequence) or a Cycles validation scene. The
pixel: the middle one (in raster order) of those at least 6 pixels from an object edge and 8 from
the frame's border."""
import argparse
import pathlib
import sys

import numpy as np

import rtdenoise as rtd
from energy_parts import edge_mask, sequence_paths

METHODS = ("jbf", "atrous", "temporal", "svgf", "detail")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("sequence")
    parser.add_argument("--frames", default="0,5")
    parser.add_argument("--value", type=float, default=1000.0)
    parser.add_argument("--no-energy", action="store_true")
    args = parser.parse_args()
    source, _ = sequence_paths(args.sequence)
    seq = rtd.open_sequence(source)
    whens = [int(w) for w in args.frames.split(",")]
    frames = [seq[i] for i in range(min(len(seq), max(whens) + 2))]
    away = edge_mask(np.asarray(frames[0].ids), 6)
    away[:8, :] = away[-8:, :] = False  # and from the frame's border
    away[:, :8] = away[:, -8:] = False
    ys, xs = np.nonzero(away)
    if len(ys) == 0:
        sys.exit(f"{args.sequence}: no pixel 6 pixels from an object edge")
    y, x = ys[len(ys) // 2], xs[len(xs) // 2]
    print(f"pixel ({x}, {y}), {args.value:g}x its 7x7 neighbourhood's mean, energy "
          f"{'off' if args.no_energy else 'on'}")
    print(f"{'frame':>5} {'method':<9} {'pixel':>7} {'15x15 max':>9} {'next frame':>10}")
    for when in whens:
        for method in METHODS:
            luminance = {}
            for firefly in (False, True):
                den = rtd.Denoiser(method, energy=not args.no_energy)
                out = []
                for t, f in enumerate(frames):
                    inputs = f.inputs()
                    color = np.array(inputs["color"], np.float32)[..., :3].copy()
                    if firefly and t == when:
                        around = color[max(0, y - 3): y + 4, max(0, x - 3): x + 4].mean()
                        color[y, x, :] = args.value * max(float(around), 1e-3)
                    inputs["color"] = color
                    out.append(den.denoise(**inputs).mean(axis=2))
                den.close()
                luminance[firefly] = out
            ratio = luminance[True][when] / np.maximum(luminance[False][when], 1e-6)
            window = ratio[max(0, y - 7): y + 8, max(0, x - 7): x + 8]
            following = min(when + 1, len(frames) - 1)
            next_ratio = luminance[True][following][y, x] / max(
                luminance[False][following][y, x], 1e-6)
            print(f"{when:>5} {method:<9} {ratio[y, x]:>6.2f}x {window.max():>8.2f}x "
                  f"{next_ratio:>9.2f}x", flush=True)


if __name__ == "__main__":
    main()
