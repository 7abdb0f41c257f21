#!/usr/bin/env python3
"""Per sequence: the share of geometry pixels whose 1-spp radiance is black (paths that found no
light), over every third frame. The share predicts, weakly, where svgf leads `detail`
(docs/validation.md, 2026-12-06). A sequence is a generated one (scripts/make_corpus.sh) or a
Cycles scene's noisy/ folder (scripts/validation_scenes.sh): anything `rtdenoise` reads."""
import argparse

import numpy as np
import rtdenoise as rtd


def luminance(a):
    return 0.2126 * a[..., 0] + 0.7152 * a[..., 1] + 0.0722 * a[..., 2]


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("sequences", nargs="+")
    args = parser.parse_args()
    for path in args.sequences:
        sequence = rtd.open_sequence(path)
        shares = []
        for i in range(0, len(sequence), 3):
            frame = sequence[i]
            geometry = np.asarray(frame.ids).reshape(frame.shape[0], frame.shape[1]) >= 0
            colour = np.asarray(frame.color)[..., :3]
            shares.append(np.mean(luminance(colour)[geometry] <= 1e-6))
        print(f"{path:48s} black {np.mean(shares):.3f}")


if __name__ == "__main__":
    main()
