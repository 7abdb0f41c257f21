#!/usr/bin/env python3
"""The validation protocol's table (issue 38; docs/corpus.md): every method on every validation
set, with relMSE, PSNR, SSIM, temporal error and the energy ratio, and the train set beside it
(the gap between them says how much was fitted). Nothing here chooses anything: it only reports.

  scripts/validation_table.py [--corpus cache/corpus] [--cycles cache/validation_scenes]
                              [--builtin cache/builtin] [--methods input,svgf,detail]
                              (a method "learned=FILE": the learned method with FILE's weights)
                              [--train-limit N] [--jobs 1]

Sets (each skipped, saying so, where its folder is missing):
  - corpus/validation/seed_*  and  corpus/train/seed_*  (scripts/make_corpus.sh)
  - cycles/<scene>/noisy with cycles/<scene>/reference (scripts/validation_scenes.sh), and the
    equal-sample renders cycles/<scene>/results/spp<N>: the Cycles sample count each method
    matches
  - builtin/<scene> (rendered here when missing: the five built-in scenes, 128x128, 8 frames,
    256-spp references, as scripts/quality_table.sh)
The method "input" is the noisy frames themselves. Means over a set's sequences; the energy ratio
is the mean of the sequences' (each the whole sequence's output mean over its reference's), with
its smallest and largest; "tiles 5-95 %" are the 5th and 95th percentiles of the energy ratios of
32x32 tiles away from object edges (scripts/energy_parts.py's measure: every frame summed), over
the set's tiles.
Environment: RTDENOISE (default build/release/rtdenoise); the Python module on PYTHONPATH
(build/release/python) and numpy for the tiles."""
import argparse
import functools
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

import rtdenoise as rtd
from energy_parts import edge_mask, tile_sums

ROOT = pathlib.Path(__file__).resolve().parent.parent
BIN = pathlib.Path(os.environ.get("RTDENOISE", ROOT / "build/release/rtdenoise"))
EXTRA_FLAGS = []  # --flags: given to every method but the input
BUILTIN = ["moving-objects", "camera-pan", "thin-geometry", "switching-light", "reflections"]


def run(*args):
    subprocess.run([str(a) for a in args], check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.PIPE)


@functools.cache
def has_no_energy():
    """Whether the build has --no-energy (asked once)."""
    return "--no-energy" in subprocess.run([BIN, "denoise", "--help"], capture_output=True,
                                           text=True).stdout


def score(sequence, reference, method, work):
    """compare's mean metrics of `method` on `sequence` against `reference`."""
    out = work / f"{sequence.parent.name}-{sequence.name}-{method.replace('/', '_')}"
    args = ["--method", method]
    if "=" in method:  # learned=FILE: the learned method with the weights file FILE
        name, weights = method.split("=", 1)
        args = ["--method", name, "--weights", weights]
    if method == "input":  # a 0-radius JBF without firefly removal is the identity
        args = ["--method", "jbf", "--radius", "0", "--no-outlier", "--no-albedo"]
        if has_no_energy():
            args.append("--no-energy")  # (builds before 2026-12-05 have no such option)
    if method != "input":
        args += EXTRA_FLAGS
    run(BIN, "denoise", sequence, "-o", out, "-q", *args)
    report = out.with_suffix(".json")
    run(BIN, "compare", out, reference, "--json", report, "-q")
    metrics = json.loads(report.read_text())["mean"]
    metrics["tiles"] = tile_ratios(sequence, out, reference)
    return metrics


_masks = {}


def tile_ratios(sequence, results, reference, tile=32):
    """The energy ratios of the tiles away from object edges, every frame summed (energy_parts)."""
    if sequence not in _masks:
        seq = rtd.open_sequence(sequence)
        _masks[sequence] = [edge_mask(np.asarray(seq[i].ids)) for i in range(len(seq))]
    masks = _masks[sequence]
    outs = sorted(results.glob("result_*.exr"), key=lambda p: int(p.stem.split("_")[1]))
    refs = sorted(reference.glob("*.exr"), key=lambda p: int(p.stem.split("_")[-1]))
    so = sr = counts = None
    ref_total = pixels = 0.0
    for mask, o, r in zip(masks, outs, refs):
        out_image, ref_image = rtd.read_exr(o)[..., :3], rtd.read_exr(r)[..., :3]
        a, c = tile_sums(out_image, mask, tile)
        b, _ = tile_sums(ref_image, mask, tile)
        so, sr, counts = (a, b, c) if so is None else (so + a, sr + b, counts + c)
        ref_total += float(ref_image.mean(axis=2).sum())
        pixels += mask.size
    keep = (counts >= 0.5 * len(masks) * tile * tile) & (
        sr / np.maximum(counts, 1) >= 0.05 * ref_total / pixels)
    return list((so[keep] / sr[keep]).astype(float))


def relmse_of(folder, reference, work):
    report = work / f"{folder.parent.name}-{folder.name}.json"
    run(BIN, "compare", folder, reference, "--json", report, "-q")
    return json.loads(report.read_text())["mean"]["rel_mse"]


def matching_spp(relmse, ladder):
    """The sample count whose equal-sample render has this relMSE (log-log interpolation over
    the ladder [(spp, relMSE)]; '<N' or '>N' beyond its ends)."""
    ladder = sorted(ladder)
    if not ladder:
        return "-"
    if relmse >= ladder[0][1]:
        return f"<{ladder[0][0]}"
    if relmse <= ladder[-1][1]:
        return f">{ladder[-1][0]}"
    for (s0, e0), (s1, e1) in zip(ladder, ladder[1:]):
        if e1 <= relmse <= e0:
            t = (math.log(relmse) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return f"{math.exp(math.log(s0) + t * (math.log(s1) - math.log(s0))):.0f}"
    return "-"


def fmt(v, spec):
    return "-" if v is None else format(v, spec)


def row(name, method, rows, spp="-"):
    mean = lambda key: sum(r[key] for r in rows) / len(rows) if all(
        r[key] is not None for r in rows) else None
    energies = [r["energy_ratio"] for r in rows if r["energy_ratio"] is not None]
    energy = (f"{sum(energies) / len(energies):.3f} ({min(energies):.3f}-{max(energies):.3f})"
              if energies else "-")
    tiles = [t for r in rows for t in r["tiles"]]
    tile_range = (f"{np.percentile(tiles, 5):.3f}-{np.percentile(tiles, 95):.3f}" if tiles
                  else "-")
    return (f"| {name} | {method} | {len(rows)} | {fmt(mean('rel_mse'), '.4f')} | "
            f"{fmt(mean('psnr'), '.2f')} | {fmt(mean('ssim'), '.3f')} | "
            f"{fmt(mean('temporal_error'), '.4f')} | {energy} | {tile_range} | {spp} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--corpus", default=ROOT / "cache/corpus", type=pathlib.Path)
    parser.add_argument("--cycles", default=ROOT / "cache/validation_scenes", type=pathlib.Path)
    parser.add_argument("--builtin", default=ROOT / "cache/builtin", type=pathlib.Path)
    parser.add_argument("--methods", default="input,svgf,detail")
    parser.add_argument("--sets", default="validation,train,cycles,builtin",
                        help="which sets to score (comma-separated)")
    parser.add_argument("--flags", default="",
                        help="extra `rtdenoise denoise` flags for every method but the input, "
                        "e.g. --flags=--energy-frame-share=0 (a setting's before and after)")
    parser.add_argument("--train-limit", type=int, default=0,
                        help="score only the first N train sequences (0: all)")
    options = parser.parse_args()
    EXTRA_FLAGS.extend(options.flags.split())
    methods = options.methods.split(",")
    print("| set | method | sequences | relMSE | PSNR (dB) | SSIM | temporal error | "
          "energy ratio (min-max) | tiles 5-95 % | matches spp |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        work = pathlib.Path(tmp)
        sets = []
        wanted = options.sets.split(",")
        for name in [n for n in ("validation", "train") if n in wanted]:
            # Complete sequences only: a render in progress is seed_N.partial.
            seeds = sorted((s for s in (options.corpus / name).glob("seed_*")
                            if (s / "complete").exists()),
                           key=lambda p: int(p.name.split("_")[1]))
            if name == "train" and options.train_limit:
                seeds = seeds[: options.train_limit]
            if seeds:
                sets.append((f"generated {name}", [(s, s / "reference") for s in seeds], None))
            else:
                print(f"(no generated {name} set in {options.corpus})", file=sys.stderr)
        cycles = sorted(p for p in options.cycles.glob("*") if (p / "noisy").is_dir())
        for scene in cycles if "cycles" in wanted else []:
            noisy = len(list((scene / "noisy").glob("*.exr")))
            if len(list((scene / "reference").glob("*.exr"))) < noisy:
                print(f"(Cycles {scene.name}: its references are not all rendered; skipped)",
                      file=sys.stderr)
                continue
            # results/spp<N>: the equal-sample renders named as compare reads results.
            ladder = [(int(p.name[3:]), relmse_of(p, scene / "reference", work))
                      for p in sorted((scene / "results").glob("spp*")) if p.name[3:].isdigit()]
            sets.append((f"Cycles {scene.name}", [(scene / "noisy", scene / "reference")], ladder))
        if not options.cycles.is_dir():
            print(f"(no Cycles scenes in {options.cycles})", file=sys.stderr)
        for scene in BUILTIN if "builtin" in wanted else []:
            folder = options.builtin / scene
            if not (folder / "reference").is_dir():
                run(BIN, "render", scene, "-o", folder, "--width", 128, "--height", 128,
                    "--frames", 8, "--ref-spp", 256, "-q")
            sets.append((f"built-in {scene}", [(folder, folder / "reference")], None))
        for name, sequences, ladder in sets:
            for method in methods:
                rows = [score(seq, ref, method, work) for seq, ref in sequences]
                spp = matching_spp(rows[0]["rel_mse"], ladder) if ladder else "-"
                print(row(name, method, rows, spp), flush=True)


if __name__ == "__main__":
    main()
