#!/usr/bin/env python3
"""Where the image's energy goes, by kind of pixel (issue 38, item 1; docs/energy.md): each
sequence's light in the reference, the noisy input and each configuration's output, summed over
every frame in four classes of pixels, as shares of the reference's whole light:

  light  reference luminance over 20x the frame's mean (lights seen directly, their reflections)
  near   within 2 px of a light pixel
  edge   within 2 px of an object edge or the background (energy_parts.py's tile mask)
  rest   the others

  PYTHONPATH=build/release/python:scripts scripts/energy_split.py SEQ... \\
      [--config NAME:METHOD[:key=value,...][@ENV=V;ENV=V]]... [--light-at 20]

Without --config: svgf and detail. A method that loses light in one class while the input holds
it there is the method's loss; where the input itself misses it (16 frames at 1 spp against a
256-spp reference), no denoiser can give it back. The last rows sum each class over the sequences
(each sequence weighted alike: its shares)."""
import argparse
import pathlib

import numpy as np

import rtdenoise as rtd
from energy_parts import edge_mask, environment, parse_configs, sequence_paths
from relmse_outliers import distance_to, luminance

CLASSES = ("light", "near", "edge", "rest")


def pixel_classes(reference, ids, light_at):
    lum = luminance(reference)
    light = lum > light_at * lum.mean()
    distance = distance_to(light, 4)
    away = edge_mask(ids)
    return np.where(distance == 0, 0, np.where(distance <= 2, 1, np.where(~away, 2, 3)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("sequences", nargs="+")
    parser.add_argument("--config", action="append", default=[])
    parser.add_argument("--light-at", type=float, default=20.0,
                        help="a light pixel: reference luminance over this times the frame's mean")
    args = parser.parse_args()
    configs, environments = parse_configs(args.config or ["svgf", "detail"])
    names = ["reference", "input"] + [c[0] for c in configs]
    print(f"{'sequence':<24} {'class':<6} {'pixels':>7} " + " ".join(f"{n:>10}" for n in names))
    totals = {c: np.zeros(len(names) + 1) for c in CLASSES}
    for folder in args.sequences:
        source, ref_paths = sequence_paths(folder)
        seq = rtd.open_sequence(source)
        frames = [seq[i] for i in range(len(seq))]
        refs = [rtd.read_exr(p)[..., :3] for p in ref_paths]
        outputs = []
        for name, method, settings in configs:
            with environment(environments.get(name, {})):
                den = rtd.Denoiser(method, **settings)
                outputs.append([luminance(den.denoise(**f.inputs())) for f in frames])
                den.close()
        sums = np.zeros((len(CLASSES), len(names) + 1))  # + the pixel count
        for t, (f, r) in enumerate(zip(frames, refs)):
            cls = pixel_classes(r, np.asarray(f.ids), args.light_at)
            images = [luminance(r), luminance(np.asarray(f.inputs()["color"])[..., :3])]
            images += [o[t] for o in outputs]
            for c in range(len(CLASSES)):
                mask = cls == c
                sums[c, :-1] += [float(im[mask].sum(dtype=np.float64)) for im in images]
                sums[c, -1] += mask.mean() / len(frames)
        whole = sums[:, 0].sum()
        for c, label in enumerate(CLASSES):
            shares = sums[c, :-1] / whole
            totals[label] += np.append(shares, sums[c, -1]) / len(args.sequences)
            print(f"{pathlib.Path(folder).name:<24} {label:<6} {sums[c, -1]:7.4f} "
                  + " ".join(f"{s:10.4f}" for s in shares), flush=True)
    if len(args.sequences) > 1:
        for label in CLASSES:
            t = totals[label]
            print(f"{'mean':<24} {label:<6} {t[-1]:7.4f} " + " ".join(f"{s:10.4f}" for s in t[:-1]))


if __name__ == "__main__":
    main()
