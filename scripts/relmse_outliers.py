#!/usr/bin/env python3
"""Where a method's relMSE comes from (issue 39; docs/learned.md): per-pixel relMSE of two
configurations on sequences with references, the share of each one's relMSE sum held by its worst
pixels, and where the pixels that make the second worse than the first lie: how bright their
reference is, and how far they are from a light seen directly (a reference pixel over 20x the
frame's mean luminance).

  PYTHONPATH=build/release/python:scripts scripts/relmse_outliers.py SEQ... \\
      [--config NAME:METHOD[:key=value,...]] [--config ...] [--top 0.001]

Without --config: detail against learned. relMSE as src/metrics: mean over pixels and channels of
(x - r)^2 / (r^2 + 0.01)."""
import argparse
import pathlib

import numpy as np

import rtdenoise as rtd
from energy_parts import parse_config, sequence_paths

EPSILON = 0.01


def luminance(image):
    return 0.2126 * image[..., 0] + 0.7152 * image[..., 1] + 0.0722 * image[..., 2]


def distance_to(mask, limit=16):
    """Chebyshev distance of every pixel to the nearest True pixel of mask, capped at limit."""
    distance = np.full(mask.shape, limit, dtype=np.int32)
    reached = mask.copy()
    distance[reached] = 0
    for d in range(1, limit):
        grown = reached.copy()
        grown[1:, :] |= reached[:-1, :]
        grown[:-1, :] |= reached[1:, :]
        grown[:, 1:] |= reached[:, :-1]
        grown[:, :-1] |= reached[:, 1:]
        grown[1:, 1:] |= reached[:-1, :-1]
        grown[:-1, :-1] |= reached[1:, 1:]
        grown[1:, :-1] |= reached[:-1, 1:]
        grown[:-1, 1:] |= reached[1:, :-1]
        distance[grown & ~reached] = d
        reached = grown
    return distance


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("sequences", nargs="+")
    parser.add_argument("--config", action="append", default=[])
    parser.add_argument("--top", type=float, default=0.001, help="share of pixels called worst")
    args = parser.parse_args()
    configs = [parse_config(c) for c in args.config] or [("detail", "detail", {}),
                                                        ("learned", "learned", {})]
    if len(configs) != 2:
        parser.error("two --config: the first is the baseline")
    bins = [0, 1, 2, 4, 8, 16]
    for folder in args.sequences:
        source, ref_paths = sequence_paths(folder)
        seq = rtd.open_sequence(source)
        frames = [seq[i] for i in range(len(seq))]
        refs = [rtd.read_exr(p)[..., :3].astype(np.float64) for p in ref_paths]
        maps = []
        for _, method, settings in configs:
            den = rtd.Denoiser(method, **settings)
            outs = [den.denoise(**f.inputs())[..., :3].astype(np.float64) for f in frames]
            den.close()
            maps.append(np.stack([((o - r) ** 2 / (r * r + EPSILON)).mean(axis=2)
                                  for o, r in zip(outs, refs)]))
        ref_lum = np.stack([luminance(r) for r in refs])
        lights = np.stack([distance_to(l > 20.0 * l.mean()) for l in ref_lum])
        name = pathlib.Path(folder).name
        for (cname, _, _), m in zip(configs, maps):
            flat = np.sort(m.ravel())[::-1]
            worst = max(1, int(args.top * flat.size))
            print(f"{name} {cname}: relMSE {m.mean():.4f}; worst {args.top:.1%} of pixels hold "
                  f"{flat[:worst].sum() / flat.sum():.1%} of it")
        excess = maps[1] - maps[0]
        total = excess[excess > 0].sum()
        print(f"{name}: {configs[1][0]} - {configs[0][0]} = {maps[1].mean() - maps[0].mean():+.4f}"
              f" (the pixels where it is worse sum to {total / excess.size:+.4f})")
        for lo, hi in zip(bins, bins[1:] + [None]):
            sel = (lights >= lo) & (lights < hi) if hi else lights >= lo
            if not sel.any():
                continue
            part = excess[sel & (excess > 0)].sum()
            print(f"  distance to a light {lo:>2}-{(hi - 1) if hi else 'far':>3} px: "
                  f"{sel.mean():6.2%} of pixels, {part / max(total, 1e-30):6.1%} of the excess, "
                  f"mean relMSE {maps[0][sel].mean():9.4f} -> {maps[1][sel].mean():9.4f}, "
                  f"reference luminance median {np.median(ref_lum[sel]):.3f}")


if __name__ == "__main__":
    main()
