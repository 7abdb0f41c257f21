"""Stage 2: the pixel-sample dataset, built once per corpus and cached.

Corpus (scripts/make_corpus.sh, docs/corpus.md): DIR/train/seed_<n>/ and DIR/validation/seed_<n>/
are sequence folders with converged frames in reference/reference_<i>.exr (or Blender's numbered
reference/0001.exr, ...: the first is frame 0's), and DIR/manifest.json records the generator.

For each sequence, `rtdenoise denoise SEQ --method learned --debug -o CACHE/<set>/seed_<n>` writes
learned-inputs/learned-inputs_<i>.exr (the 29 channels of features.CHANNELS); a dump folder is
reused when its `complete` marker records the same command and program (sha256). Then, per
frame pair (t-1, t), t >= 1, a seeded set of foreground pixels of frame t (all of them if fewer)
is drawn, the same pixels in both frames:

    raw_prev, raw   (N, 29) float32   the dumped channels at frames t-1 and t
    ref_prev, ref   (N, 3)  float32   the references' RGB at frames t-1 and t
    sequence, frame (N,)    int32     the sequence's seed and t
    pixel           (N, 2)  int32     y, x
    meta            JSON text         corpus, generator version, seeds, samples per frame, ...

saved as CACHE/<set>-spf<S>-seed<seed>[-max<M>].npz (float32). The random draw of a pair depends
only on (seed, sequence seed, t), so adding sequences does not change the others' samples.

    /usr/bin/python3 training/dataset.py --corpus DIR --rtdenoise build/release/rtdenoise \\
        [--cache DIR] [--samples-per-frame 2048] [--seed 1] [--max-sequences N] [--device cpu]
"""

import argparse
import hashlib
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import time

import numpy as np

from features import CHANNELS, FOREGROUND

SETS = ("train", "validation")
FORMAT = "rtdenoise-learned-samples 1"


def _rtdenoise_module():
    try:
        import rtdenoise
    except ImportError:
        build = pathlib.Path(__file__).resolve().parents[1] / "build" / "release" / "python"
        sys.path.insert(0, str(build))
        try:
            import rtdenoise
        except ImportError as e:
            sys.exit(f"dataset.py: the rtdenoise Python module is not importable ({e}); build it "
                     f"(cmake --build --preset release) or set PYTHONPATH=build/release/python")
    return rtdenoise


def generator_version(corpus):
    manifest = pathlib.Path(corpus) / "manifest.json"
    if not manifest.is_file():
        return "unknown (no manifest.json)"
    return json.loads(manifest.read_text()).get("generator", "unknown")


def sequences(corpus, set_name, max_sequences=None):
    """[(seed, folder)] of DIR/<set>/seed_<n>, by seed (make_corpus.sh renders into
    seed_<n>.partial and renames when complete: a partial folder does not match)."""
    folder = pathlib.Path(corpus) / set_name
    found = []
    for path in folder.glob("seed_*") if folder.is_dir() else []:
        m = re.fullmatch(r"seed_(\d+)", path.name)
        if m and path.is_dir():
            found.append((int(m.group(1)), path))
    found.sort()
    return found[:max_sequences] if max_sequences else found


def numbered(folder, prefix):
    """{number: path} of folder/<prefix>_<number>.exr."""
    out = {}
    for path in pathlib.Path(folder).glob(f"{prefix}_*.exr"):
        m = re.fullmatch(re.escape(prefix) + r"_(\d+)\.exr", path.name)
        if m:
            out[int(m.group(1))] = path
    return out


def dump_files(folder):
    """{number: path} of a denoise output folder's dumps: OUT/learned-inputs/learned-inputs_<n>.exr
    (or, as the first builds wrote them, OUT/learned-inputs_<n>.exr)."""
    folder = pathlib.Path(folder)
    return numbered(folder / "learned-inputs", "learned-inputs") or numbered(folder,
                                                                               "learned-inputs")


def reference_files(sequence, numbers):
    """{number: reference EXR} for the dumped frame numbers."""
    ref = pathlib.Path(sequence) / "reference"
    named = numbered(ref, "reference")
    if all(n in named for n in numbers):
        return {n: named[n] for n in numbers}
    plain = sorted((p for p in ref.glob("*.exr") if re.fullmatch(r"\d+\.exr", p.name)),
                   key=lambda p: int(p.stem))
    first = min(numbers)
    if plain and all(0 <= n - first < len(plain) for n in numbers):
        return {n: plain[n - first] for n in numbers}
    missing = [n for n in numbers if n not in named]
    raise FileNotFoundError(f"{ref}: no reference_<i>.exr for frames {missing[:5]}")


def binary_digest(path):
    """sha256 of the rtdenoise program: dumps of another build are made again."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def dump_sequence(rtdenoise_bin, sequence, dump_dir, denoise_args=(), log=print):
    """Runs the denoiser's --debug dump into dump_dir unless a complete one is there; returns
    {number: learned-inputs EXR}."""
    dump_dir = pathlib.Path(dump_dir)
    command = [str(rtdenoise_bin), "denoise", str(pathlib.Path(sequence).resolve()), "--method",
               "learned", "--debug",
               "-q", *map(str, denoise_args)]
    marker = dump_dir / "complete"
    record = {"command": command[1:] + ["-o", "<dir>"], "sha256": binary_digest(rtdenoise_bin)}
    if marker.is_file():
        try:
            old = json.loads(marker.read_text())
            if all(old.get(k) == record[k] for k in ("command", "sha256")):
                dumps = dump_files(dump_dir)
                if dumps:
                    return dumps
        except json.JSONDecodeError:
            pass
    partial = dump_dir.with_name(dump_dir.name + ".partial")
    shutil.rmtree(partial, ignore_errors=True)
    partial.parent.mkdir(parents=True, exist_ok=True)
    start = time.time()
    run = subprocess.run(command + ["-o", str(partial)], capture_output=True, text=True)
    if run.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} -o {partial} failed ({run.returncode}):\n"
                           f"{run.stderr.strip()[-2000:]}")
    dumps = dump_files(partial)
    if not dumps:
        raise RuntimeError(f"{' '.join(command)} wrote no learned-inputs_<i>.exr in {partial} "
                           f"(does this rtdenoise have --method learned's --debug dump?)")
    record["seconds"] = round(time.time() - start, 2)
    record["version"] = subprocess.run([str(rtdenoise_bin), "--version"], capture_output=True,
                                       text=True).stdout.strip()
    (partial / "complete").write_text(json.dumps(record) + "\n")
    shutil.rmtree(dump_dir, ignore_errors=True)
    os.replace(partial, dump_dir)
    log(f"  dumped {sequence} -> {dump_dir} ({record['seconds']} s)")
    return dump_files(dump_dir)


def sample_pairs(raw_frames, ref_frames, numbers, sequence_seed, seed, samples_per_frame):
    """Samples of consecutive frame pairs. raw_frames/ref_frames: {number: (H, W, 29|3)}."""
    parts = []
    for t in numbers:
        if t - 1 not in raw_frames:
            continue
        a, b = raw_frames[t - 1], raw_frames[t]
        ra, rb = ref_frames[t - 1], ref_frames[t]
        ok = (b[..., FOREGROUND] > 0.5)
        for image in (a, b, ra, rb):
            ok &= np.all(np.isfinite(image), axis=-1)
        ys, xs = np.nonzero(ok)
        rng = np.random.default_rng([seed, sequence_seed, t])
        if len(ys) > samples_per_frame:
            pick = np.sort(rng.choice(len(ys), samples_per_frame, replace=False))
            ys, xs = ys[pick], xs[pick]
        n = len(ys)
        parts.append({
            "raw_prev": a[ys, xs], "raw": b[ys, xs], "ref_prev": ra[ys, xs], "ref": rb[ys, xs],
            "sequence": np.full(n, sequence_seed, np.int32), "frame": np.full(n, t, np.int32),
            "pixel": np.stack([ys, xs], axis=1).astype(np.int32),
        })
    return parts


def concatenate(parts):
    keys = ("raw_prev", "raw", "ref_prev", "ref", "sequence", "frame", "pixel")
    if not parts:
        return {"raw_prev": np.zeros((0, 29), np.float32), "raw": np.zeros((0, 29), np.float32),
                "ref_prev": np.zeros((0, 3), np.float32), "ref": np.zeros((0, 3), np.float32),
                "sequence": np.zeros(0, np.int32), "frame": np.zeros(0, np.int32),
                "pixel": np.zeros((0, 2), np.int32)}
    out = {k: np.concatenate([p[k] for p in parts]) for k in keys}
    for k in ("raw_prev", "raw", "ref_prev", "ref"):
        out[k] = out[k].astype(np.float32)
    return out


def set_path(cache, set_name, samples_per_frame, seed, max_sequences):
    suffix = f"-max{max_sequences}" if max_sequences else ""
    return pathlib.Path(cache) / f"{set_name}-spf{samples_per_frame}-seed{seed}{suffix}.npz"


def load_set(path):
    with np.load(path, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    data["meta"] = json.loads(str(data["meta"]))
    return data


def build_set(corpus, set_name, rtdenoise_bin, cache, samples_per_frame=2048, seed=1,
              max_sequences=None, denoise_args=("--device", "cpu"), log=print):
    """The set's samples (dict of arrays + "meta"), from CACHE's .npz when it matches."""
    corpus, cache = pathlib.Path(corpus), pathlib.Path(cache)
    seqs = sequences(corpus, set_name, max_sequences)
    if not seqs:
        raise FileNotFoundError(f"{corpus}/{set_name}: no seed_<n> sequence folders")
    meta = {
        "format": FORMAT, "corpus": str(corpus.resolve()), "set": set_name,
        "generator": generator_version(corpus), "sequence_seeds": [s for s, _ in seqs],
        "samples_per_frame": samples_per_frame, "sample_seed": seed,
        "denoise_args": list(map(str, denoise_args)), "channels": CHANNELS,
        "rtdenoise_sha256": binary_digest(rtdenoise_bin),
    }
    path = set_path(cache, set_name, samples_per_frame, seed, max_sequences)
    if path.is_file():
        data = load_set(path)
        old = {k: v for k, v in data["meta"].items() if k in meta}
        if old == meta:
            log(f"{set_name}: {len(data['raw'])} samples from {path}")
            return data
        log(f"{set_name}: {path} was built from other inputs; rebuilding")
    rtd = _rtdenoise_module()
    parts, markers = [], []
    start = time.time()
    for sequence_seed, folder in seqs:
        dump_dir = cache / set_name / f"seed_{sequence_seed}"
        dumps = dump_sequence(rtdenoise_bin, folder, dump_dir, denoise_args, log)
        marker = json.loads((dump_dir / "complete").read_text())
        markers.append(f"{marker.get('version', '')} sha256 {marker.get('sha256', '')[:16]}")
        numbers = sorted(dumps)
        refs = reference_files(folder, numbers)
        raw = {n: rtd.read_exr(dumps[n], channels=CHANNELS) for n in numbers}
        ref = {n: rtd.read_exr(refs[n])[..., :3] for n in numbers}
        for n in numbers:
            if raw[n].shape[:2] != ref[n].shape[:2]:
                raise ValueError(f"{dumps[n]} is {raw[n].shape[:2]}, {refs[n]} {ref[n].shape[:2]}")
        parts += sample_pairs(raw, ref, numbers, sequence_seed, seed, samples_per_frame)
    data = concatenate(parts)
    meta["rtdenoise"] = sorted(set(markers))
    meta["built"] = time.strftime("%Y-%m-%d %H:%M:%S")
    meta["seconds"] = round(time.time() - start, 1)
    cache.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.stem + ".partial.npz")
    np.savez(tmp, meta=np.array(json.dumps(meta)), **data)
    os.replace(tmp, path)
    log(f"{set_name}: {len(data['raw'])} samples of {len(seqs)} sequences -> {path} "
        f"({meta['seconds']} s)")
    data["meta"] = meta
    return data


def default_cache(corpus):
    root = pathlib.Path(__file__).resolve().parents[1]
    return root / "cache" / "learned_dataset" / pathlib.Path(corpus).resolve().name


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--corpus", required=True)
    p.add_argument("--rtdenoise", default="build/release/rtdenoise")
    p.add_argument("--cache", help="default: cache/learned_dataset/<corpus folder name>")
    p.add_argument("--samples-per-frame", type=int, default=2048)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--max-sequences", type=int)
    p.add_argument("--sets", default="train,validation")
    p.add_argument("--device", default="cpu", help="rtdenoise denoise --device for the dumps "
                   "(default cpu: the same dumps on every machine)")
    p.add_argument("--denoise-arg", action="append", default=[],
                   help="another argument for rtdenoise denoise (repeat for each word), e.g. "
                        "--denoise-arg=--weights --denoise-arg=FILE")
    a = p.parse_args(argv)
    cache = a.cache or default_cache(a.corpus)
    for name in a.sets.split(","):
        d = build_set(a.corpus, name, a.rtdenoise, cache, a.samples_per_frame, a.seed,
                      a.max_sequences, ["--device", a.device, *a.denoise_arg])
        print(f"{name}: {len(d['raw'])} samples, {len(d['meta']['sequence_seeds'])} sequences, "
              f"generator {d['meta']['generator']}")


if __name__ == "__main__":
    main()


def synthetic_samples(count, seed=0, frames_per_sequence=8):
    """A synthetic set in build_set's layout, for tests and dry runs (no renderer): per sample a
    clean demodulated radiance c (log-uniform 1e-2..1e2); candidates L_k = c (1 + b_k) + n_k with
    noise n_k shrinking with k (the A-Trous levels) and a bias b_k (blur across an edge, a
    per-sample amount) growing with k; V_k the luminance variance of n_k; the reference
    albedo * c. The frame t-1 holds the same pixel with new noise and c changed a little."""
    rng = np.random.default_rng(seed)

    def frame(c, history, edge, albedo):
        raw = np.zeros((count, 29), np.float32)
        lum_c = (c @ np.array([0.2126, 0.7152, 0.0722]))[:, None]
        sigma0 = 0.8 * lum_c / np.sqrt(np.maximum(history, 1.0))[:, None] + 1e-3
        for k in range(6):
            sigma = sigma0 * 0.55 ** k
            bias = edge * (0.35 * k) * rng.standard_normal((count, 1))
            noisy = c * (1.0 + bias) + sigma * rng.standard_normal((count, 3))
            raw[:, 4 * k: 4 * k + 3] = np.maximum(noisy, 0.0)
            raw[:, 4 * k + 3] = (sigma[:, 0] ** 2) * rng.uniform(0.5, 1.5, count)
        raw[:, 24] = history
        raw[:, 25:28] = albedo
        raw[:, 28] = 1.0
        return raw

    c = np.exp(rng.uniform(np.log(1e-2), np.log(1e2), (count, 1)))
    c = c * rng.uniform(0.5, 1.0, (count, 3))
    c_prev = c * rng.uniform(0.9, 1.1, (count, 1))
    history = rng.integers(0, 41, count).astype(np.float32)
    edge = (rng.uniform(size=(count, 1)) < 0.4).astype(np.float64)
    albedo = rng.uniform(0.1, 1.0, (count, 3))
    raw = frame(c, history, edge, albedo)
    raw_prev = frame(c_prev, np.maximum(history - 1, 0), edge, albedo)
    sequence = (np.arange(count) // max(1, count // 4)).astype(np.int32)
    return {
        "raw_prev": raw_prev, "raw": raw,
        "ref_prev": (albedo * c_prev).astype(np.float32), "ref": (albedo * c).astype(np.float32),
        "sequence": sequence,
        "frame": (np.arange(count) % frames_per_sequence + 1).astype(np.int32),
        "pixel": np.zeros((count, 2), np.int32),
        "meta": {"format": FORMAT, "generator": f"synthetic (seed {seed})", "sequence_seeds": [],
                 "samples_per_frame": 0, "sample_seed": seed, "set": "synthetic"},
    }
