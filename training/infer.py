"""Stage 7: the network and filter in PyTorch on the denoiser's dumps, to check the C++ inference.

    /usr/bin/python3 training/infer.py --weights W DUMP -o OUT [--compare DIR]
        DUMP: a learned-inputs_<n>.exr, a folder of them, or the DIR of `rtdenoise denoise SEQ
        --method learned --debug -o DIR` (its learned-inputs/ subfolder); OUT: result_<n>.exr
        per dump into the folder OUT (or the file OUT when DUMP is one file and OUT ends with
        .exr). --compare DIR: the largest difference from DIR/result_<n>.exr (the C++ results
        of the same run and weights; run the denoiser with --no-energy for this: the energy pass
        follows the mix).
    /usr/bin/python3 training/infer.py --weights tests/data/learned_known_answer_weights.txt \
        --known-answer tests/data/learned_known_answer.txt
        the known answer a C++ test checks (known_answer below).

Functions: run(weights, raw) -> (H, W, 3); known_answer(weights, out_path).
"""

import argparse
import os
import pathlib
import re
import sys

import numpy as np
import torch

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

from export import checksum_of, load_weights  # noqa: E402
from features import CHANNELS, FOREGROUND, features, features_float64  # noqa: E402
from model import FoldedMix, clamp_to_range  # noqa: E402


def _rtdenoise():
    try:
        import rtdenoise
    except ImportError:
        sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "build" / "release"
                               / "python"))
        import rtdenoise
    return rtdenoise


def _weights(weights):
    return load_weights(weights) if isinstance(weights, (str, os.PathLike)) else weights


@torch.no_grad()
def run(weights, raw, return_mix=False):
    """The filtered radiance of (..., 29) float32 inputs (numpy or torch) with a weights file's
    arrays (or its path): float32 numpy (..., 3); with return_mix also the (..., 6) softmax."""
    net = FoldedMix(_weights(weights))
    out, w = net(torch.as_tensor(np.asarray(raw, np.float32)), return_weights=True)
    return (out.numpy(), w.numpy()) if return_mix else out.numpy()


def _float64_reference(weights, raw):
    """The same computation in float64 (features, network, filter)."""
    w = {k: torch.as_tensor(v, dtype=torch.float64) for k, v in _weights(weights).items()
         if k != "trained"}
    raw = torch.as_tensor(np.asarray(raw, np.float64))
    f = features_float64(raw)
    h = torch.relu(f @ w["w1"].T + w["b1"])
    h = torch.relu(h @ w["w2"].T + w["b2"])
    mix = torch.softmax(h @ w["w3"].T + w["b3"], dim=-1)
    cand = raw[..., :24].reshape(*raw.shape[:-1], 6, 4)[..., :3]
    mixed = (mix[..., None] * cand).sum(-2)
    mixed = clamp_to_range(mixed, cand, raw[..., 3])
    fg = raw[..., FOREGROUND:FOREGROUND + 1] > 0.5
    return f.numpy(), (raw[..., 25:28] * torch.where(fg, mixed, cand[..., 0, :])).numpy()


def known_answer_inputs(width=8, height=6, seed=2026):
    """A deterministic synthetic input, (height*width, 29) float32, row by row:
    pixel 0 background; 1 all-zero radiance (ref at its 1e-4 floor); 2 every variance 0;
    3 one candidate (L3) with a tiny variance (1e-12); 4 a slightly negative L0 variance
    (-1e-7: the max(V, 0)); 5 a strong edge (L1..L5 far from L0: softsign near +-1); 6 a dark
    edge the other way; 7 history 0.5 (fractional); the others radiance log-spaced over
    1e-3..1e3 with candidates drifting level to level, variances from 1e-4 to 10x the squared
    luminance, history over 0..40 (integers and fractions), albedo 0.05..1."""
    rng = np.random.default_rng(seed)
    n = width * height
    raw = np.zeros((n, 29), np.float64)
    levels = np.logspace(-3, 3, n)
    rng.shuffle(levels)
    histories = np.concatenate([[0, 1, 2, 3, 4, 5, 7.25, 8, 12, 16, 24, 31, 31.5, 32, 33, 40],
                                rng.uniform(0, 40, n)])[:n]
    for i in range(n):
        base = levels[i] * rng.uniform(0.3, 1.0, 3)
        drift = 1.0
        for k in range(6):
            drift *= np.exp(rng.normal(0.0, 0.25))
            raw[i, 4 * k: 4 * k + 3] = base * drift * rng.uniform(0.8, 1.25, 3)
            lum = 0.2126 * raw[i, 4 * k] + 0.7152 * raw[i, 4 * k + 1] + 0.0722 * raw[i, 4 * k + 2]
            raw[i, 4 * k + 3] = lum * lum * 10.0 ** rng.uniform(-4, 1) * 0.5 ** k
        raw[i, 24] = histories[i]
        raw[i, 25:28] = rng.uniform(0.05, 1.0, 3)
        raw[i, 28] = 1.0
    raw[0, 28] = 0.0                                   # background: albedo * L0
    raw[1, :24] = 0.0                                  # black
    raw[2, 3:24:4] = 0.0                               # no variance
    raw[3, 15] = 1e-12                                 # L3: tiny variance
    raw[4, 3] = -1e-7                                  # negative L0 variance
    raw[5, 4:24] = raw[5, 4:24] * np.repeat([3.0, 6.0, 12.0, 24.0, 48.0], 4)  # edge up
    raw[6, 4:24] = raw[6, 4:24] * np.repeat([0.3, 0.1, 0.03, 0.01, 0.003], 4)  # edge down
    raw[7, 24] = 0.5
    return raw.astype(np.float32)


def known_answer(weights, out_path, width=8, height=6):
    """Writes the known-answer file the C++ test parses: '#' header lines, then one line per
    pixel (row by row): 29 inputs (features.CHANNELS order), the 14 features, the 3 outputs,
    all '%.9g' (float32 values: they read back exactly)."""
    w = _weights(weights)
    raw = known_answer_inputs(width, height)
    f32 = features(torch.from_numpy(raw)).numpy()
    out, mix = run(w, raw, return_mix=True)
    f64, out64 = _float64_reference(w, raw)
    feature_gap = float(np.max(np.abs(f32 - f64)))
    output_gap = float(np.max(np.abs(out - out64) / np.maximum(np.abs(out64), 1e-3)))
    name = os.path.basename(os.fspath(weights)) if isinstance(weights, (str, os.PathLike)) else "?"
    checksum = checksum_of(weights) if isinstance(weights, (str, os.PathLike)) else "?"
    header = [
        "rtdenoise learned method: known answer (docs/learned_spec.md), written by",
        f"training/infer.py known_answer. Weights: {name} (fnv1a32 {checksum}).",
        f"pixels {width * height}: width {width}, height {height}, row by row.",
        "Each line: 29 inputs, 14 features, 3 outputs (R G B); 46 numbers, all %.9g of float32.",
        "Inputs: " + " ".join(CHANNELS) + ".",
        "Features f0..f13 in float32 as the spec writes them (computed for background pixels",
        "too); outputs = albedo * clamp(sum_k w_k L_k.rgb, min(E, L5), max(E, L5)) (foreground;",
        "E: L0 drawn towards L5 by its noise, model.range_end)",
        "or albedo * L0.rgb (background).",
        "Pixel 0 background; 1 black; 2 no variance; 3 L3 variance 1e-12; 4 L0 variance -1e-7;",
        "5 and 6 strong edges; 7 history 0.5; others: radiance 1e-3..1e3, history 0..40.",
        f"The same formulas in float64 differ by at most {feature_gap:.3g} (features, absolute)",
        f"and {output_gap:.3g} (outputs, relative to max(|out|, 1e-3)). Softmax weights per pixel:",
        "min max-weight %.3f, max max-weight %.3f." % (mix.max(-1).min(), mix.max(-1).max()),
    ]
    lines = ["# " + h for h in header]
    for i in range(raw.shape[0]):
        values = list(raw[i]) + list(f32[i]) + list(out[i])
        lines.append(" ".join("%.9g" % float(v) for v in values))
    pathlib.Path(out_path).write_text("\n".join(lines) + "\n")
    return {"features_gap": feature_gap, "output_gap": output_gap}


def read_known_answer(path):
    """(inputs (N, 29), features (N, 14), outputs (N, 3)) of a known-answer file."""
    rows = [list(map(float, line.split())) for line in open(path)
            if line.strip() and not line.startswith("#")]
    a = np.array(rows, np.float32)
    return a[:, :29], a[:, 29:43], a[:, 43:46]


def dumps_of(path):
    path = pathlib.Path(path)
    if path.is_file():
        m = re.search(r"_(\d+)\.exr$", path.name)
        return {int(m.group(1)) if m else 0: path}
    out = {}
    for folder in (path / "learned-inputs", path):  # OUT/learned-inputs/, or a folder of dumps
        for p in folder.glob("learned-inputs_*.exr"):
            m = re.fullmatch(r"learned-inputs_(\d+)\.exr", p.name)
            if m:
                out[int(m.group(1))] = p
        if out:
            break
    return dict(sorted(out.items()))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--weights", required=True)
    p.add_argument("dump", nargs="?", help="learned-inputs_<n>.exr or a folder of them")
    p.add_argument("-o", "--output")
    p.add_argument("--compare", help="folder of the C++ result_<n>.exr to compare with")
    p.add_argument("--known-answer", metavar="PATH", help="write the known-answer file")
    a = p.parse_args(argv)
    weights = load_weights(a.weights)
    if a.known_answer:
        gaps = known_answer(a.weights, a.known_answer)
        print(f"wrote {a.known_answer} (float64 gaps: features {gaps['features_gap']:.3g}, "
              f"outputs {gaps['output_gap']:.3g})")
        if not a.dump:
            return
    if not a.dump or not a.output:
        p.error("DUMP and -o OUT are needed (or --known-answer PATH)")
    rtd = _rtdenoise()
    dumps = dumps_of(a.dump)
    if not dumps:
        sys.exit(f"infer.py: no learned-inputs_<n>.exr in {a.dump}")
    single = pathlib.Path(a.dump).is_file() and a.output.endswith(".exr")
    worst = 0.0
    for n, path in dumps.items():
        raw = rtd.read_exr(path, channels=CHANNELS)
        out = run(weights, raw)
        target = pathlib.Path(a.output) if single else pathlib.Path(a.output) / f"result_{n}.exr"
        target.parent.mkdir(parents=True, exist_ok=True)
        rtd.write_exr(target, out)
        line = f"{path} -> {target}"
        if a.compare:
            cpp = rtd.read_exr(pathlib.Path(a.compare) / f"result_{n}.exr")
            diff = np.abs(cpp - out)
            rel = float(np.max(diff / np.maximum(np.abs(out), 1e-3)))
            worst = max(worst, rel)
            line += f"; vs C++: max |diff| {diff.max():.3g}, max relative {rel:.3g}"
        print(line)
    if a.compare:
        print(f"largest relative difference from {a.compare}: {worst:.3g}")


if __name__ == "__main__":
    main()
