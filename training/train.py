"""Stage 5: trains the `learned` method's network from scratch, in one command.

    /usr/bin/python3 training/train.py --corpus DIR --rtdenoise build/release/rtdenoise \\
        --out training/runs/NAME [--steps 20000] [--batch 4096] [--lr 2e-3] [--seed 1] ...

builds (or loads from the cache) the train and validation samples (dataset.py), sets the input
normalisation from the train set, trains with Adam on random batches with augmentation (a colour
permutation of every rgb input and reference; an exposure scale s of the radiance and the
references, s^2 of the variances), validates after every epoch (loss, relMSE, energy ratio;
reported only: the weights written are the final ones, never chosen on validation), and writes
into --out:

    learned_weights.txt   the weights file (export.py; docs/learned_spec.md)
    curve.csv             step, epoch, train loss, validation loss, relMSE, L1, temporal, energy
                          ratio, seconds
    model.pt              the PyTorch state (with the normalisation)
    run.json              the options, the datasets' metadata and the final validation figures

--synthetic N trains on synthetic samples instead of a corpus (no renderer; a dry run).
Seeded and deterministic: the same options give the same weights on the same machine.
"""

import os

os.environ.setdefault("CUBLAS_WORKSPACE_CONFIG", ":4096:8")  # deterministic cuBLAS

import argparse  # noqa: E402
import csv  # noqa: E402
import json  # noqa: E402
import pathlib  # noqa: E402
import random  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import torch  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import dataset  # noqa: E402
import export  # noqa: E402
from features import FEATURES, RADIANCE_RGB, RGB_TRIPLES, VARIANCES, features  # noqa: E402
from loss import TONEMAPS, LossWeights, hdr_loss, rel_mse  # noqa: E402
from model import LearnedMix  # noqa: E402

PERMUTATIONS = torch.tensor([[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]])


def set_seeds(seed):
    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)
    torch.use_deterministic_algorithms(True)
    if torch.backends.cudnn.is_available():
        torch.backends.cudnn.benchmark = False


def to_tensors(data, device):
    return {k: torch.as_tensor(np.asarray(data[k]), device=device)
            for k in ("raw_prev", "raw", "ref_prev", "ref")}


def _column_maps():
    """(6, 29): for each colour permutation, the source channel of every raw channel."""
    maps = torch.arange(29).repeat(6, 1)
    for p, perm in enumerate(PERMUTATIONS.tolist()):
        for triple in RGB_TRIPLES:
            for c in range(3):
                maps[p, triple[c]] = triple[perm[c]]
    return maps


COLUMN_MAPS = _column_maps()
RADIANCE_MASK = torch.zeros(29)
RADIANCE_MASK[RADIANCE_RGB] = 1.0
VARIANCE_MASK = torch.zeros(29)
VARIANCE_MASK[VARIANCES] = 1.0


def augment(batch, generator, exposure_stops, permute=True):
    """The same random colour permutation (every rgb triple: L0..L5, albedo, the references)
    and exposure scale s (radiance and references x s, variances x s^2) for a sample's both
    frames. Random numbers come from `generator` (CPU), so runs repeat on any device."""
    n = batch["raw"].shape[0]
    device = batch["raw"].device
    out = dict(batch)
    if permute:
        p = torch.randint(0, 6, (n,), generator=generator)
        columns = COLUMN_MAPS[p].to(device)
        ref_columns = PERMUTATIONS[p].to(device)
        for key in ("raw_prev", "raw"):
            out[key] = torch.gather(out[key], 1, columns)
        for key in ("ref_prev", "ref"):
            out[key] = torch.gather(out[key], 1, ref_columns)
    if exposure_stops > 0:
        u = torch.rand(n, 1, generator=generator) * 2 - 1
        s = torch.exp2(u * exposure_stops)
        scale = (1 + (s - 1) * RADIANCE_MASK + (s * s - 1) * VARIANCE_MASK).to(device)
        for key in ("raw_prev", "raw"):
            out[key] = out[key] * scale
        s = s.to(device)
        for key in ("ref_prev", "ref"):
            out[key] = out[key] * s
    return out


def frame_groups(data):
    """Per sample, the index of its (sequence, frame): the energy gain's groups."""
    key = data["sequence"].astype(np.int64) * 100000 + data["frame"].astype(np.int64)
    _, group = np.unique(key, return_inverse=True)
    return torch.from_numpy(group.astype(np.int64))


LUMINANCE = torch.tensor([0.2126, 0.7152, 0.0722])


def with_frame_gain(x, ref, group, groups):
    """x scaled per frame group so that its luminance sum is the reference's, clamped to
    [0.2, 5]: what the library's energy pass (run after the mix) does per 16x16 tile from the
    noisy input's sum, here per frame of samples from the reference's (its expectation)."""
    lum = LUMINANCE.to(x.device)
    sx = torch.zeros(groups, device=x.device, dtype=x.dtype).index_add(0, group, x @ lum)
    sr = torch.zeros(groups, device=x.device, dtype=x.dtype).index_add(0, group, ref @ lum)
    gain = torch.clamp(sr / torch.clamp(sx, min=1e-8), 0.2, 5.0)
    return x * gain[group][:, None]


def normalisation(raw, chunk=1 << 18):
    """Per-feature mean and std over the samples (float64 sums)."""
    total, total_sq, n = torch.zeros(FEATURES, dtype=torch.float64), torch.zeros(
        FEATURES, dtype=torch.float64), 0
    for i in range(0, raw.shape[0], chunk):
        f = features(raw[i:i + chunk]).double().cpu()
        total += f.sum(0)
        total_sq += (f * f).sum(0)
        n += f.shape[0]
    mean = total / max(n, 1)
    std = torch.sqrt(torch.clamp(total_sq / max(n, 1) - mean * mean, min=0.0))
    return mean.float(), std.float()


@torch.no_grad()
def evaluate(model, data, weights, chunk=1 << 16, frame_gain=False):
    """The loss terms over a whole set (no augmentation), as sample-weighted means, and the
    energy ratio sum(output) / sum(reference). frame_gain: outputs scaled per frame first
    (with_frame_gain; chunks hold whole frames)."""
    sums, n, out_sum, ref_sum = {}, 0, 0.0, 0.0
    group_all = data.get("group")
    for i in range(0, data["raw"].shape[0], chunk):
        b = {k: v[i:i + chunk] for k, v in data.items()}
        x = model(b["raw"])
        x_prev = model(b["raw_prev"]) if weights.temporal > 0 else None
        if frame_gain and group_all is not None:
            g = b["group"] - b["group"].min()
            groups = int(g.max()) + 1
            x = with_frame_gain(x, b["ref"], g, groups)
            if x_prev is not None:
                x_prev = with_frame_gain(x_prev, b["ref_prev"], g, groups)
        loss, parts = hdr_loss(x, b["ref"], x_prev, b["ref_prev"], weights)
        if weights.temporal == 0:  # reported all the same
            t = TONEMAPS[weights.tonemap]
            e = t(x) - t(b["ref"])
            e_prev = t(model(b["raw_prev"])) - t(b["ref_prev"])
            parts["temporal"] = float(torch.abs(e - e_prev).mean())
        m = x.shape[0]
        parts["loss"] = float(loss)
        for k, v in parts.items():
            sums[k] = sums.get(k, 0.0) + v * m
        n += m
        out_sum += float(x.double().sum())
        ref_sum += float(b["ref"].double().sum())
    result = {k: v / max(n, 1) for k, v in sums.items()}
    result["energy_ratio"] = out_sum / ref_sum if ref_sum > 0 else float("nan")
    return result


def input_figures(data):
    """The same figures for the input L0 (albedo * L0: the accumulation before filtering)
    and the last A-Trous level L5, for comparison."""
    out = {}
    for name, k in (("L0", 0), ("L5", 5)):
        x = data["raw"][:, 25:28] * data["raw"][:, 4 * k: 4 * k + 3]
        out[name] = {"relmse": float(rel_mse(x, data["ref"])),
                     "energy_ratio": float(x.double().sum() / data["ref"].double().sum())}
    return out


def train(train_data, val_data, steps=20000, batch=4096, lr=2e-3, seed=1, weights=None,
          drop_feature=None, exposure_stops=2.0, permute=True, val_every=None, device=None,
          curve_path=None, log=print, frame_gain=False):
    """Trains a LearnedMix; returns (model, curve rows, final validation figures)."""
    set_seeds(seed)
    weights = weights or LossWeights()
    device = torch.device(device or ("cuda" if torch.cuda.is_available() else "cpu"))
    tr = to_tensors(train_data, device)
    va = to_tensors(val_data, device)
    if frame_gain:  # samples sorted by frame: each frame's samples contiguous
        for data, t in ((train_data, tr), (val_data, va)):
            if len(data["raw"]) == 0:
                continue
            group = frame_groups(data)
            order = torch.argsort(group, stable=True)
            for key in list(t):
                t[key] = t[key][order.to(device)]
            t["group"] = group[order].to(device)
    n = tr["raw"].shape[0]
    if n == 0:
        raise ValueError("the train set holds no samples")
    model = LearnedMix(drop_feature=drop_feature)
    mean, std = normalisation(tr["raw"])
    model.set_normalisation(mean, std)
    model.to(device)
    optimiser = torch.optim.Adam(model.parameters(), lr=lr)
    # Cosine decay to a tenth of lr over the run.
    schedule = torch.optim.lr_scheduler.LambdaLR(
        optimiser, lambda s: 0.1 + 0.9 * 0.5 * (1 + np.cos(np.pi * min(s, steps) / steps)))
    generator = torch.Generator().manual_seed(seed)
    epoch_steps = max(1, -(-n // batch))
    # Every epoch; on a small set, at most about 200 times in a run.
    val_every = val_every or max(epoch_steps, -(-steps // 200))
    curve, start = [], time.time()
    columns = ["step", "epoch", "train_loss", "val_loss", "val_relmse", "val_l1", "val_temporal",
               "val_energy_ratio", "seconds"]
    csv_file = open(curve_path, "w", newline="") if curve_path else None
    writer = csv.writer(csv_file) if csv_file else None
    if writer:
        writer.writerow(columns)

    def record(step, train_loss):
        model.eval()
        v = evaluate(model, va, weights, frame_gain=frame_gain) if va["raw"].shape[0] else {}
        model.train()
        row = [step, round(step / epoch_steps, 3), train_loss, v.get("loss", float("nan")),
               v.get("relmse", float("nan")), v.get("l1", float("nan")),
               v.get("temporal", float("nan")), v.get("energy_ratio", float("nan")),
               round(time.time() - start, 2)]
        curve.append(dict(zip(columns, row)))
        if writer:
            writer.writerow(["%.6g" % x if isinstance(x, float) else x for x in row])
            csv_file.flush()
        log(f"step {step:6d}  epoch {row[1]:7.2f}  train {train_loss:.5f}  val {row[3]:.5f}  "
            f"relMSE {row[4]:.5f}  temporal {row[6]:.5f}  energy {row[7]:.4f}  {row[8]:.0f} s")
        return v

    record(0, float("nan"))
    order = torch.randperm(n, generator=generator)
    position, running, running_n = 0, 0.0, 0
    final = None
    if frame_gain:  # batches of whole frames, so that each frame's gain is over all its samples
        group_size = int(torch.bincount(tr["group"]).max())
        frames_per_batch = max(1, batch // group_size)
        frame_count = int(tr["group"].max()) + 1
        starts = torch.searchsorted(tr["group"], torch.arange(frame_count, device=tr["group"].device))
        ends = torch.cat([starts[1:], torch.tensor([n], device=starts.device)])
        epoch_steps = max(1, -(-frame_count // frames_per_batch))
        frame_order = torch.randperm(frame_count, generator=generator)
    for step in range(1, steps + 1):
        if frame_gain:
            if position + frames_per_batch > frame_count:
                frame_order = torch.randperm(frame_count, generator=generator)
                position = 0
            chosen = frame_order[position:position + frames_per_batch]
            position += frames_per_batch
            idx = torch.cat([torch.arange(int(starts[f]), int(ends[f])) for f in chosen]).to(device)
        else:
            if position + batch > n:
                order = torch.randperm(n, generator=generator)
                position = 0
            idx = order[position:position + batch].to(device)
            position += batch
        b = augment({k: v[idx] for k, v in tr.items()}, generator, exposure_stops, permute)
        x = model(b["raw"])
        x_prev = model(b["raw_prev"]) if weights.temporal > 0 else None
        if frame_gain:
            g = torch.unique(b["group"], return_inverse=True)[1]
            groups = int(g.max()) + 1
            x = with_frame_gain(x, b["ref"], g, groups)
            if x_prev is not None:
                x_prev = with_frame_gain(x_prev, b["ref_prev"], g, groups)
        loss, _ = hdr_loss(x, b["ref"], x_prev, b["ref_prev"], weights)
        optimiser.zero_grad(set_to_none=True)
        loss.backward()
        optimiser.step()
        schedule.step()
        running += float(loss)
        running_n += 1
        if step % val_every == 0 or step == steps:
            final = record(step, running / running_n)
            running, running_n = 0.0, 0
    if csv_file:
        csv_file.close()
    model.eval()
    return model.cpu(), curve, final


def main(argv=None):
    p = argparse.ArgumentParser(description="Trains the learned method's network (docs/"
                                "learned_spec.md); see training/README.md")
    p.add_argument("--corpus", help="corpus folder (scripts/make_corpus.sh)")
    p.add_argument("--rtdenoise", default="build/release/rtdenoise")
    p.add_argument("--out", required=True, help="run folder (created)")
    p.add_argument("--cache", help="dataset cache (default cache/learned_dataset/<corpus name>)")
    p.add_argument("--steps", type=int, default=20000)
    p.add_argument("--batch", type=int, default=4096)
    p.add_argument("--lr", type=float, default=2e-3)
    p.add_argument("--seed", type=int, default=1, help="training seed (init, batches, "
                   "augmentation)")
    p.add_argument("--samples-per-frame", type=int, default=2048)
    p.add_argument("--data-seed", type=int, default=1, help="seed of the pixel samples")
    p.add_argument("--max-sequences", type=int, help="use only the first N sequences of each set")
    p.add_argument("--no-temporal", action="store_true", help="ablation: no temporal loss term")
    p.add_argument("--drop-feature", metavar="K[,K...]",
                   type=lambda text: [int(k) for k in text.split(",")],
                   help="ablation: features K (0..13) zeroed in training and in the exported "
                        "weights (their W1 columns are 0)")
    p.add_argument("--w-relmse", type=float, default=LossWeights.relmse)
    p.add_argument("--w-smape", type=float, default=LossWeights.smape)
    p.add_argument("--relmse-clip", type=float, default=LossWeights.relmse_clip,
                   help="each value's relMSE term at most this (0: unclipped)")
    p.add_argument("--w-l1", type=float, default=LossWeights.l1)
    p.add_argument("--w-temporal", type=float, default=LossWeights.temporal)
    p.add_argument("--tonemap", choices=["reinhard", "display", "log"], default="reinhard",
                   help="tone map of the L1 and temporal terms: x/(1+x), or the project's "
                        "display transform (ACES + sRGB)")
    p.add_argument("--no-frame-gain", action="store_true",
                   help="judge the mix as it is, not scaled per frame to the reference's light "
                        "(the library's energy pass, after the mix, restores it)")
    p.add_argument("--exposure-stops", type=float, default=2.0,
                   help="augmentation: exposure scale 2^u, u uniform in [-S, S] (0: none)")
    p.add_argument("--no-permute", action="store_true", help="no colour-permutation augmentation")
    p.add_argument("--val-every", type=int, help="steps between validations (default: an epoch, "
                   "or steps/200 if longer)")
    p.add_argument("--device", help="cpu or cuda (default: cuda when available)")
    p.add_argument("--threads", type=int, help="torch CPU threads")
    p.add_argument("--dump-device", default="cpu", help="rtdenoise denoise --device of the dumps")
    p.add_argument("--synthetic", type=int, metavar="N",
                   help="train on N synthetic samples (no corpus, no renderer): a dry run")
    a = p.parse_args(argv)
    if a.threads:
        torch.set_num_threads(a.threads)
    if a.drop_feature is not None and not all(0 <= k < FEATURES for k in a.drop_feature):
        p.error(f"--drop-feature {a.drop_feature}: features are 0..{FEATURES - 1}")
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    if a.synthetic:
        train_data = dataset.synthetic_samples(a.synthetic, seed=a.data_seed)
        val_data = dataset.synthetic_samples(max(a.synthetic // 4, 1), seed=a.data_seed + 1000)
        corpus_text = train_data["meta"]["generator"]
    else:
        if not a.corpus:
            p.error("--corpus DIR (or --synthetic N) is needed")
        cache = a.cache or dataset.default_cache(a.corpus)
        kw = dict(samples_per_frame=a.samples_per_frame, seed=a.data_seed,
                  max_sequences=a.max_sequences, denoise_args=["--device", a.dump_device])
        train_data = dataset.build_set(a.corpus, "train", a.rtdenoise, cache, **kw)
        val_data = dataset.build_set(a.corpus, "validation", a.rtdenoise, cache, **kw)
        corpus_text = train_data["meta"]["generator"]
    weights = LossWeights(relmse=a.w_relmse, smape=a.w_smape, l1=a.w_l1, relmse_clip=a.relmse_clip,
                          temporal=0.0 if a.no_temporal else a.w_temporal, tonemap=a.tonemap)
    seeds = train_data["meta"].get("sequence_seeds", [])
    seed_text = f"{seeds[0]}-{seeds[-1]}" if seeds else "synthetic"
    print(f"train: {len(train_data['raw'])} samples; validation: {len(val_data['raw'])} samples; "
          f"device {a.device or ('cuda' if torch.cuda.is_available() else 'cpu')}")
    model, curve, final = train(
        train_data, val_data, steps=a.steps, batch=a.batch, lr=a.lr, seed=a.seed, weights=weights,
        drop_feature=a.drop_feature, exposure_stops=a.exposure_stops, permute=not a.no_permute,
        val_every=a.val_every, device=a.device, curve_path=out / "curve.csv",
        frame_gain=not a.no_frame_gain)
    trained = (f"corpus {corpus_text}; train sequences {len(seeds)} (seeds {seed_text}), "
               f"{len(train_data['raw'])} samples"
               + ("" if a.synthetic else f", {a.samples_per_frame}/frame")
               + f", data seed {a.data_seed}; steps {a.steps}, batch {a.batch}, lr {a.lr:g}, "
               f"seed {a.seed}; "
               f"loss relmse {weights.relmse:g} (clip {weights.relmse_clip:g}) smape {weights.smape:g} l1 {weights.l1:g} temporal {weights.temporal:g} "
               f"{weights.tonemap}" + ("" if a.no_frame_gain else ", frame gain")
               + (f"; features {','.join(map(str, a.drop_feature))} dropped"
                  if a.drop_feature is not None else "")
               + f"; {time.strftime('%Y-%m-%d')}")
    path = export.export_model(model, out / "learned_weights.txt", trained)
    torch.save(model.state_dict(), out / "model.pt")
    va = to_tensors(val_data, "cpu")
    run = {
        "options": vars(a), "trained": trained, "weights": str(path),
        "fnv1a32": export.checksum_of(path), "final_validation": final,
        "validation_inputs": input_figures(va) if len(val_data["raw"]) else None,
        "train_meta": train_data["meta"], "validation_meta": val_data["meta"],
        "torch": torch.__version__,
    }
    (out / "run.json").write_text(json.dumps(run, indent=1, default=str) + "\n")
    print(f"wrote {path} (fnv1a32 {run['fnv1a32']}), {out / 'curve.csv'}, {out / 'run.json'}")
    if run["validation_inputs"]:
        print("validation, for comparison: " + "; ".join(
            f"albedo*{k}: relMSE {v['relmse']:.5f}, energy {v['energy_ratio']:.4f}"
            for k, v in run["validation_inputs"].items()))


if __name__ == "__main__":
    main()
