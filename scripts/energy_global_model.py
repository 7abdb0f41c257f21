#!/usr/bin/env python3
"""A numpy model of a frame-level energy gain after the tiles' restoration (the method run with
energy_frame_share=0; docs/energy.md, "The tail the tiles cut"): G_t = EMA_F(output sum + sum
of min(input - output, cap)) / EMA_F(output sum) over foreground pixels under light x their
tiles' mean, cap = phi x the frame's output sum x frames averaged (one sample lifts G by at most
phi), G within [1/gmax, gmax], applied to those pixels.

  PYTHONPATH=build/release/python:scripts scripts/energy_global_model.py SEQ...
      [--method detail] [--variants phi:F:gmax[:light],...]"""
import argparse

import numpy as np
import rtdenoise as rtd
from energy_parts import score as parts_score, sequence_paths

W = np.array([0.2126, 0.7152, 0.0722], np.float32)

FIELDS = ("energy", "tile_p5", "tile_p95", "rel_mse", "psnr", "temporal")


def score(frames, outs, refs):
    """energy_parts' figures as an array: energy, tiles 5/95 %, relMSE, PSNR, temporal."""
    figures = parts_score(frames, outs, refs, 16)
    return np.array([figures[k] for k in FIELDS])


T = 16
def tiles(x, m):
    h, w = x.shape
    th, tw = (h + T - 1) // T, (w + T - 1) // T
    q = np.zeros((th * T, tw * T)); q[:h, :w] = x * m
    return q.reshape(th, T, tw, T).sum(axis=(1, 3))

def smooth(g):
    q = np.pad(g, 1, mode="edge")
    return sum(q[1 + dy: 1 + dy + g.shape[0], 1 + dx: 1 + dx + g.shape[1]]
               for dy in (-1, 0, 1) for dx in (-1, 0, 1))

def local_mean(lo, m):
    g = smooth(tiles(lo, m)) / np.maximum(smooth(tiles(np.ones_like(lo), m)), 1)
    h, w = lo.shape
    return np.kron(g, np.ones((T, T)))[:h, :w]

def globalize(frames, outs, phi, F, gmax, light=128.0):
    A = B = None; res = []; n = 0
    for f, o in zip(frames, outs):
        m0 = np.asarray(f.ids) >= 0
        lo = np.maximum(o @ W, 0)
        m = m0 & (lo <= light * local_mean(lo, m0)) if light > 0 else m0
        li = np.maximum(np.asarray(f.color)[..., :3] @ W, 0)
        so = float(lo[m].sum())
        n = min(n + 1, F); a = 1.0 / n
        cap = phi * max(so, 1e-12) / a
        si = so + float(np.minimum(li[m] - lo[m], cap).sum())
        A = si if A is None else A + a * (si - A)
        B = so if B is None else B + a * (so - B)
        g = float(np.clip(A / B, 1 / gmax, gmax)) if B > 1e-20 else 1.0
        res.append(np.where(m[..., None], o * g, o).astype(np.float32))
    return res

p = argparse.ArgumentParser()
p.add_argument("sequences", nargs="+")
p.add_argument("--method", default="detail")
p.add_argument("--variants", default="0.01:32:1.25")
a = p.parse_args()
variants = [tuple(float(x) for x in v.split(":")) for v in a.variants.split(",")]
rows = {"base": [], "input": []}
for v in variants: rows[v] = []
for s in a.sequences:
    src, refp = sequence_paths(s)
    seq = rtd.open_sequence(src); frames = [seq[i] for i in range(len(seq))]
    refs = [rtd.read_exr(q)[..., :3] for q in refp]
    den = rtd.Denoiser(a.method, energy_frame_share=0); outs = [den.denoise(**f.inputs()) for f in frames]; den.close()
    ins = [np.asarray(f.color)[..., :3].astype(np.float32) for f in frames]
    ein = sum(float(x.sum(dtype=np.float64)) for x in ins) / sum(float(r.sum(dtype=np.float64)) for r in refs)
    b = score(frames, outs, refs); rows["base"].append(b); rows["input"].append(ein)
    line = [s.rstrip('/').split('/')[-1], f"in {ein:.3f}", "base " + " ".join(f"{x:.4f}" for x in b)]
    for v in variants:
        r = score(frames, globalize(frames, outs, v[0], int(v[1]), v[2], v[3] if len(v) > 3 else 128.0), refs); rows[v].append(r)
        line.append(f"{v}: e {r[0]:.4f} dPSNR {r[4]-b[4]:+.3f} relMSE x{r[3]/b[3]:.3f} T x{r[5]/b[5]:.3f}")
    print(" | ".join(line), flush=True)
B = np.array(rows["base"])
print("columns: energy tile5 tile95 relMSE PSNR temporal")
print("MEAN input energy", f"{np.mean(rows['input']):.4f}")
print("MEAN base", " ".join(f"{x:.4f}" for x in B.mean(0)))
for v in variants:
    R = np.array(rows[v])
    print("MEAN", v, " ".join(f"{x:.4f}" for x in R.mean(0)),
          f"geo relMSE x{np.exp(np.mean(np.log(R[:,3]/B[:,3]))):.4f} dPSNR {np.mean(R[:,4]-B[:,4]):+.4f} T x{np.exp(np.mean(np.log(R[:,5]/B[:,5]))):.4f}")
