#!/usr/bin/env python3
"""A numpy model of the energy restoration (kernels/energy.h; docs/energy.md), to compare its
variants on the train set before building one: a method's output without the restoration
(`energy=False`), then per TILE x TILE tile the capped input's and the output's luminance sums,
averaged over up to FRAMES frames, their 3x3-tent ratio within [0.2, 5] as a gain, interpolated
between tile centres. Prints per sequence and their mean: energy, tiles 5-95 % (16x16), relMSE,
PSNR, temporal error, without ("base") and with ("gain") the modelled restoration.

  PYTHONPATH=build/release/python scripts/energy_model.py SEQ... [--method detail] [--tile 16]
      [--cap 128] [--frames 4] [--denominator averaged|current] [--luminance-power 0]

--denominator current: the gain is the averaged input over this frame's output; --luminance-power
g: the added light is spread over a tile's pixels in proportion to luminance^(1+g) (0: uniform).
The model caps samples at cap x the output's mean (the pass: the larger of the input's and the
output's, and a cap that grows with the frames averaged), so its figures differ slightly."""
import argparse

import numpy as np

import rtdenoise as rtd
from energy_parts import edge_mask, sequence_paths, tile_sums


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("sequences", nargs="+")
    parser.add_argument("--method", default="detail")
    parser.add_argument("--tile", type=int, default=16)
    parser.add_argument("--cap", type=float, default=128.0)
    parser.add_argument("--frames", type=float, default=4.0)
    parser.add_argument("--denominator", choices=("averaged", "current"), default="averaged")
    parser.add_argument("--luminance-power", type=float, default=0.0)
    args = parser.parse_args()
    T = args.tile

    def lum(a):
        return a @ np.array([0.2126, 0.7152, 0.0722], np.float32)

    def tiles(x, m):
        h, w = x.shape
        th, tw = (h + T - 1) // T, (w + T - 1) // T
        p = np.zeros((th * T, tw * T))
        p[:h, :w] = x * m
        return p.reshape(th, T, tw, T).sum(axis=(1, 3))

    def smooth(g):
        p = np.pad(g, 1, mode="edge")
        return sum(p[1 + dy: 1 + dy + g.shape[0], 1 + dx: 1 + dx + g.shape[1]]
                   * (2 - abs(dx)) * (2 - abs(dy)) for dy in (-1, 0, 1) for dx in (-1, 0, 1)) / 16

    def upsample(g, h, w):
        th, tw = g.shape
        ys = (np.arange(h) + 0.5) / T - 0.5
        xs = (np.arange(w) + 0.5) / T - 0.5
        y0 = np.clip(np.floor(ys).astype(int), 0, th - 1)
        y1 = np.clip(y0 + 1, 0, th - 1)
        fy = np.clip(ys - np.floor(ys), 0, 1)[:, None]
        x0 = np.clip(np.floor(xs).astype(int), 0, tw - 1)
        x1 = np.clip(x0 + 1, 0, tw - 1)
        fx = np.clip(xs - np.floor(xs), 0, 1)[None, :]
        return ((g[y0][:, x0] * (1 - fx) + g[y0][:, x1] * fx) * (1 - fy)
                + (g[y1][:, x0] * (1 - fx) + g[y1][:, x1] * fx) * fy)

    def scores(frames, outs, refs):
        fm = rtd.compare(outs, refs).frames
        e = sum(x.sum(dtype=np.float64) for x in outs) / sum(r.sum(dtype=np.float64) for r in refs)
        to = tr = cn = None
        for f, o, r in zip(frames, outs, refs):
            mask = edge_mask(np.asarray(f.ids))
            a, c = tile_sums(o, mask, 16)
            b, _ = tile_sums(r, mask, 16)
            to, tr, cn = (a, b, c) if to is None else (to + a, tr + b, cn + c)
        total = sum(r.sum() for r in refs)
        keep = (cn >= 0.5 * len(frames) * 256) & (
            tr / np.maximum(cn, 1) >= 0.05 * total / sum(r[..., 0].size for r in refs) / 3)
        ratios = to[keep] / tr[keep] if keep.any() else np.array([np.nan])
        return (e, np.percentile(ratios, 5), np.percentile(ratios, 95),
                np.mean([x.relmse for x in fm]), np.mean([x.psnr for x in fm]),
                np.mean([x.temporal_error for x in fm[1:]]))

    results = {"base": [], "gain": []}
    for sequence in args.sequences:
        source, ref_paths = sequence_paths(sequence)
        seq = rtd.open_sequence(source)
        frames = [seq[i] for i in range(len(seq))]
        refs = [rtd.read_exr(p)[..., :3] for p in ref_paths]
        den = rtd.Denoiser(args.method, energy=False)
        outs = [den.denoise(**f.inputs()) for f in frames]
        den.close()
        A = B = None
        fixed = []
        for t, (f, o) in enumerate(zip(frames, outs)):
            m = (np.asarray(f.ids) >= 0).astype(float)
            h, w = m.shape
            lo = lum(o)
            so, n = tiles(lo, m), tiles(np.ones_like(lo), m)
            mean_out = upsample(smooth(so) / np.maximum(smooth(n), 1e-6), h, w)
            m = m * ~(lo > args.cap * mean_out)  # lights seen directly: neither counted nor scaled
            raw = np.minimum(lum(np.asarray(f.color)[..., :3]), args.cap * mean_out)
            so, sr = tiles(lo, m), tiles(raw, m)
            a = max(1 / (t + 1), 1 / args.frames)
            A = sr if A is None else (1 - a) * A + a * sr
            B = so if B is None or args.denominator == "current" else (1 - a) * B + a * so
            gain = upsample(np.clip(smooth(A) / np.maximum(smooth(B), 1e-9), 0.2, 5.0), h, w)
            g = args.luminance_power
            lp = np.maximum(lo, 0)
            weight = (upsample(smooth(tiles(lp, m)), h, w)
                      / np.maximum(upsample(smooth(tiles(lp ** (1 + g), m)), h, w), 1e-12)
                      * lp ** g)
            fixed.append(np.where(m[..., None] > 0, o * (1 + (gain - 1) * weight)[..., None], o)
                         .astype(np.float32))
        for name, images in (("base", outs), ("gain", fixed)):
            row = scores(frames, images, refs)
            results[name].append(row)
            print(sequence.rstrip("/").split("/")[-1], name, " ".join(f"{v:.4f}" for v in row),
                  flush=True)
    print("columns: energy tile5 tile95 relMSE PSNR temporal")
    for name, rows in results.items():
        print("MEAN", name, " ".join(f"{x:.4f}" for x in np.mean(rows, axis=0)))


if __name__ == "__main__":
    main()
