#!/usr/bin/env python3
"""Where a method loses the image's energy (issue 38, item 1; docs/energy.md): each method, and
each variant with one part switched off, on sequences with references, with the energy ratio of
the whole sequence (output mean over reference mean), of 32x32 tiles away from object edges (5th
and 95th percentile), relMSE, PSNR and the temporal error.

  scripts/energy_parts.py SEQ... [--config NAME:METHOD[:key=value,...][@ENV=V;ENV=V]]...
                          [--tile 32] [--json F] [--cli BIN]

SEQ: a folder with `reference/` (course layout, a generated corpus's sequence) or a Cycles
validation scene (`noisy/` and `reference/`). Without --config: every method at its defaults.
Example: --config svgf:svgf --config svgf-no-outlier:svgf:outlier=false
@ENV=V: environment variables set for that configuration alone (a prototype's switches,
docs/experiments/*.patch: one build serves every configuration). Over several sequences it also
prints each configuration against the first: the geometric mean of the per-sequence relMSE
ratios, the mean PSNR gain and the mean temporal-error ratio.
A tile is kept where at least half its pixels are away (2 px) from an object edge and the
background, and its reference mean is at least 5 % of the frame's; its ratio sums every frame.
Needs the Python module (build/release/python on PYTHONPATH) and numpy. --cli BIN denoises with
that build's command instead (`rtdenoise denoise`, the settings as its flags): another build's
figures, e.g. a commit before a change."""
import argparse
import contextlib
import json
import os
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

import rtdenoise as rtd


def parse_config(text):
    name, _, rest = text.partition(":")
    method, _, settings = rest.partition(":")
    values = {}
    for item in filter(None, settings.split(",")):
        key, _, value = item.partition("=")
        if value.lower() in ("true", "false"):
            values[key] = value.lower() == "true"
        else:
            try:
                values[key] = int(value)
            except ValueError:
                try:
                    values[key] = float(value)
                except ValueError:
                    values[key] = value  # a path (weights=FILE)
    return name, method or name, values


def parse_configs(texts):
    """--config texts into (name, method, settings) and each name's environment (@ENV=V;...)."""
    configs, environments = [], {}
    for text in texts:
        spec, _, env = text.partition("@")
        configs.append(parse_config(spec))
        environments[configs[-1][0]] = dict(e.split("=", 1) for e in env.split(";") if e)
    return configs, environments


@contextlib.contextmanager
def environment(variables):
    """The process environment with `variables` set, restored after."""
    saved = dict(os.environ)
    os.environ.update(variables)
    try:
        yield
    finally:
        os.environ.clear()
        os.environ.update(saved)


def sequence_paths(folder):
    folder = pathlib.Path(folder)
    if (folder / "noisy").is_dir():
        refs = sorted((folder / "reference").glob("*.exr"))
        return folder / "noisy", refs
    refs = sorted((folder / "reference").glob("reference_*.exr"),
                  key=lambda p: int(p.stem.split("_")[1]))
    return folder, refs


def edge_mask(ids, reach=2):
    """True away from object edges and the background."""
    edge = ids < 0
    for axis in (0, 1):
        diff = np.diff(ids, axis=axis) != 0
        pad = [(0, 0), (0, 0)]
        pad[axis] = (0, 1)
        edge |= np.pad(diff, pad)
        pad[axis] = (1, 0)
        edge |= np.pad(diff, pad)
    grown = edge.copy()
    for _ in range(reach):
        g = grown.copy()
        g[1:, :] |= grown[:-1, :]
        g[:-1, :] |= grown[1:, :]
        g[:, 1:] |= grown[:, :-1]
        g[:, :-1] |= grown[:, 1:]
        grown = g
    return ~grown


def tile_sums(image, mask, tile):
    h, w = mask.shape
    th, tw = h // tile, w // tile
    lum = image[: th * tile, : tw * tile].mean(axis=2) * mask[: th * tile, : tw * tile]
    sums = lum.reshape(th, tile, tw, tile).sum(axis=(1, 3))
    counts = mask[: th * tile, : tw * tile].reshape(th, tile, tw, tile).sum(axis=(1, 3))
    return sums, counts


def denoise_with_cli(cli, source, method, settings):
    flags = []
    for key, value in settings.items():
        if isinstance(value, bool):
            flags.append(f"--{key}" if value else f"--no-{key}")
        else:
            flags += [f"--{key}", str(value)]
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([cli, "denoise", str(source), "-o", out, "-q", "--method", method, *flags],
                       check=True)
        results = sorted(pathlib.Path(out).glob("result_*.exr"),
                         key=lambda p: int(p.stem.split("_")[1]))
        return [rtd.read_exr(p)[..., :3] for p in results]


def evaluate(frames, refs, method, settings, tile, cli=None, source=None):
    if cli:
        outs = denoise_with_cli(cli, source, method, settings)
    else:
        den = rtd.Denoiser(method, **settings)
        outs = [den.denoise(**f.inputs()) for f in frames]
        den.close()
    return score(frames, outs, refs, tile)


def score(frames, outs, refs, tile):
    """The figures of `outs` against `refs`: energy, its tile percentiles, relMSE, PSNR, temporal."""
    comparison = rtd.compare(outs, refs)
    frame_metrics = comparison.frames
    out_sum = sum(float(o.sum(dtype=np.float64)) for o in outs)
    ref_sum = sum(float(r.sum(dtype=np.float64)) for r in refs)
    tiles_out = tiles_ref = counts = None
    for f, o, r in zip(frames, outs, refs):
        mask = edge_mask(np.asarray(f.ids))
        so, c = tile_sums(o, mask, tile)
        sr, _ = tile_sums(r, mask, tile)
        tiles_out = so if tiles_out is None else tiles_out + so
        tiles_ref = sr if tiles_ref is None else tiles_ref + sr
        counts = c if counts is None else counts + c
    keep = (counts >= 0.5 * len(frames) * tile * tile) & (
        tiles_ref / np.maximum(counts, 1) >= 0.05 * ref_sum / sum(r[..., 0].size for r in refs) / 3)
    ratios = (tiles_out[keep] / tiles_ref[keep]) if keep.any() else np.array([np.nan])
    temporal = [m.temporal_error for m in frame_metrics if m.temporal_error is not None]
    return {
        "energy": out_sum / ref_sum,
        "tile_p5": float(np.percentile(ratios, 5)),
        "tile_p95": float(np.percentile(ratios, 95)),
        "tiles": int(keep.sum()),
        "rel_mse": float(np.mean([m.relmse for m in frame_metrics])),
        "psnr": float(np.mean([m.psnr for m in frame_metrics])),
        "temporal": float(np.mean(temporal)) if temporal else float("nan"),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("sequences", nargs="+")
    parser.add_argument("--config", action="append", default=[])
    parser.add_argument("--tile", type=int, default=32)
    parser.add_argument("--json")
    parser.add_argument("--cli", help="denoise with this build's rtdenoise command")
    args = parser.parse_args()
    configs, environments = parse_configs(args.config)
    configs = configs or [(m, m, {}) for m in ("jbf", "atrous", "temporal", "svgf", "detail")]
    results = {}
    print(f"{'sequence':<28} {'config':<22} {'energy':>7} {'tile5':>6} {'tile95':>6} "
          f"{'relMSE':>8} {'PSNR':>6} {'temporal':>9}")
    for folder in args.sequences:
        source, ref_paths = sequence_paths(folder)
        seq = rtd.open_sequence(source)
        frames = [seq[i] for i in range(len(seq))]
        refs = [rtd.read_exr(p)[..., :3] for p in ref_paths]
        if len(refs) != len(frames):
            sys.exit(f"{folder}: {len(frames)} frames, {len(refs)} references")
        for name, method, settings in configs:
            with environment(environments.get(name, {})):
                r = evaluate(frames, refs, method, settings, args.tile, args.cli, source)
            results.setdefault(str(folder), {})[name] = r
            print(f"{pathlib.Path(folder).name:<28} {name:<22} {r['energy']:7.3f} "
                  f"{r['tile_p5']:6.3f} {r['tile_p95']:6.3f} {r['rel_mse']:8.4f} "
                  f"{r['psnr']:6.2f} {r['temporal']:9.5f}", flush=True)
    if len(args.sequences) > 1:
        for name, _, _ in configs:
            rows = [results[s][name] for s in results]
            mean = {k: float(np.mean([r[k] for r in rows])) for k in rows[0]}
            print(f"{'mean':<28} {name:<22} {mean['energy']:7.3f} {mean['tile_p5']:6.3f} "
                  f"{mean['tile_p95']:6.3f} {mean['rel_mse']:8.4f} {mean['psnr']:6.2f} "
                  f"{mean['temporal']:9.5f}")
        base = configs[0][0]
        print(f"against {base}: relMSE ratio (geometric mean), PSNR gain, temporal-error ratio")
        for name, _, _ in configs:
            def per_sequence(f):
                return [f(results[s][name], results[s][base]) for s in results]
            ratio = np.exp(np.mean(per_sequence(lambda r, b: np.log(r["rel_mse"] / b["rel_mse"]))))
            gain = np.mean(per_sequence(lambda r, b: r["psnr"] - b["psnr"]))
            temporal = np.mean(per_sequence(lambda r, b: r["temporal"] / b["temporal"]))
            print(f"{name:<22} {ratio:6.3f} {gain:+7.3f} {temporal:6.3f}")
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
