"""training/ (the learned method's training code, docs/learned_spec.md): a smoke test on a
synthetic dataset (no renderer): the loss falls, the weights file round-trips and damaged copies
are refused, the augmentation keeps inputs and references together, the known answer holds.
Needs PyTorch (Debian: apt-get install python3-torch); skipped without it."""

import pathlib
import sys

import numpy as np
import pytest

try:
    import torch
except ImportError as error:  # pragma: no cover - depends on the machine
    print(f"test_training.py skipped: PyTorch is not importable ({error})")
    pytest.skip(f"PyTorch is not importable ({error}): apt-get install python3-torch",
                allow_module_level=True)

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(SOURCE_DIR / "training"))

import dataset  # noqa: E402
import export  # noqa: E402
import infer  # noqa: E402
from features import CHANNELS, features, features_float64  # noqa: E402
from model import FoldedMix  # noqa: E402
from train import augment, train  # noqa: E402

torch.set_num_threads(1)


@pytest.fixture(scope="module")
def trained():
    train_data = dataset.synthetic_samples(4096, seed=3)
    val_data = dataset.synthetic_samples(1024, seed=4)
    model, curve, final = train(train_data, val_data, steps=40, batch=512, lr=3e-3, seed=5,
                                val_every=20, device="cpu", log=lambda *_: None)
    return model, curve, final, val_data


def test_the_loss_falls(trained):
    _, curve, final, _ = trained
    assert [row["step"] for row in curve] == [0, 20, 40]
    assert curve[-1]["val_loss"] < 0.95 * curve[0]["val_loss"], curve
    assert curve[-1]["train_loss"] < curve[1]["train_loss"], curve
    assert 0.9 < final["energy_ratio"] < 1.1 and np.isfinite(final["relmse"])


def test_training_repeats():
    data = dataset.synthetic_samples(1024, seed=3)
    runs = [train(data, data, steps=5, batch=256, seed=9, device="cpu", log=lambda *_: None)[0]
            for _ in range(2)]
    for a, b in zip(runs[0].parameters(), runs[1].parameters()):
        assert torch.equal(a, b)


def test_a_dropped_feature_is_ignored_in_the_exported_file(tmp_path):
    data = dataset.synthetic_samples(512, seed=3)
    model = train(data, data, steps=3, batch=128, seed=2, drop_feature=4, device="cpu",
                  log=lambda *_: None)[0]
    weights = export.load_weights(export.export_model(model, tmp_path / "w.txt", "drop 4"))
    assert np.all(weights["w1"][:, 4] == 0) and np.any(weights["w1"][:, 3] != 0)
    # The file's network gives the same mix whatever feature 4 holds.
    net = FoldedMix(weights)
    f = features(torch.from_numpy(data["raw"][:64]))
    g = f.clone()
    g[:, 4] = torch.linspace(-1, 1, 64)
    assert torch.equal(net.mix_weights(f), net.mix_weights(g))


def test_the_weights_file_round_trips_and_refuses_damage(trained, tmp_path):
    model, _, _, val_data = trained
    path = export.export_model(model, tmp_path / "w.txt", "synthetic smoke test")
    weights = export.load_weights(path)
    folded = model.folded()
    for name in export.BLOCKS:
        np.testing.assert_array_equal(weights[name], folded[name])  # %.9g: float32 exactly
    assert weights["trained"] == "synthetic smoke test"
    text = path.read_bytes()
    assert text.endswith(b"\n") and text.splitlines()[-1].startswith(b"fnv1a32 ")
    # The file's network (normalisation folded in) computes what the trained model does.
    raw = val_data["raw"][:256]
    with torch.no_grad():
        expected = model(torch.from_numpy(raw)).numpy()
    np.testing.assert_allclose(infer.run(path, raw), expected, rtol=2e-5, atol=1e-6)

    truncated = tmp_path / "truncated.txt"
    truncated.write_bytes(text[: len(text) // 2])
    with pytest.raises(export.WeightsError, match="checksum"):
        export.load_weights(truncated)
    edited = tmp_path / "edited.txt"
    at = text.index(b"\nw2 ") + 10
    while not chr(text[at]).isdigit():
        at += 1
    digit = b"1" if text[at:at + 1] != b"1" else b"2"
    edited.write_bytes(text[:at] + digit + text[at + 1:])
    with pytest.raises(export.WeightsError, match="checksum"):
        export.load_weights(edited)
    for old, new, problem in ((b"rtdenoise-weights 2", b"rtdenoise-weights 3", "header"),
                              (b" 16 6\n", b" 16 7\n", "network"),
                              (b"l0-margin 2\n", b"l0-margin 1\n", "range"),
                              (b"rtdenoise-weights 2", b"rtdenoise-weights 1", "format 1")):
        bad = tmp_path / "header.txt"
        changed = text.replace(old, new, 1)
        body = changed[: changed.rindex(b"\nfnv1a32 ") + 1]
        bad.write_bytes(body + b"fnv1a32 %08x\n" % export.fnv1a32(body))
        with pytest.raises(export.WeightsError, match=problem):
            export.load_weights(bad)


def test_features_follow_the_spec():
    raw = dataset.synthetic_samples(64, seed=7)["raw"]
    raw[0, 3] = -1e-7  # a negative variance counts as 0
    f = features(torch.from_numpy(raw)).numpy()
    assert f.shape == (64, 14) and f.dtype == np.float32 and len(CHANNELS) == 29
    np.testing.assert_allclose(f, features_float64(torch.from_numpy(raw)).numpy(), atol=1e-5)
    history = raw[:, 24]
    np.testing.assert_allclose(f[:, 1], np.minimum(history, 32) / 32, rtol=1e-6)
    np.testing.assert_allclose(f[:, 2], 1 / np.maximum(history, 1), rtol=1e-6)
    assert np.all(np.abs(f[:, 3:8]) < 1) and np.all(f[:, 8:] >= 0) and f[0, 0] == 0


def test_background_pixels_pass_albedo_times_l0(trained, tmp_path):
    model, _, _, val_data = trained
    raw = val_data["raw"][:8].copy()
    raw[:, 28] = 0.0
    with torch.no_grad():
        out = model(torch.from_numpy(raw)).numpy()
    np.testing.assert_array_equal(out, raw[:, 25:28] * raw[:, 0:3])


def test_augmentation_keeps_inputs_and_references_together():
    n = 64
    batch = {"raw": torch.arange(1, 30, dtype=torch.float32).repeat(n, 1),
             "raw_prev": 100 + torch.arange(1, 30, dtype=torch.float32).repeat(n, 1),
             "ref": torch.tensor([[1000.0, 2000.0, 3000.0]]).repeat(n, 1),
             "ref_prev": torch.tensor([[4000.0, 5000.0, 6000.0]]).repeat(n, 1)}
    # A permutation only: every rgb triple (L0..L5, albedo) permuted as the references are.
    out = augment(batch, torch.Generator().manual_seed(1), exposure_stops=0.0)
    perm = (out["ref"] / 1000 - 1).long()
    assert len({tuple(p) for p in perm.tolist()}) > 1
    assert torch.equal((out["ref_prev"] / 1000 - 4).long(), perm)
    for key in ("raw", "raw_prev"):
        for start in (0, 4, 8, 12, 16, 20, 25):
            assert torch.equal(out[key][:, start:start + 3] - batch[key][:, start:start + 1],
                               perm.float())
        for unchanged in (3, 7, 11, 15, 19, 23, 24, 28):
            assert torch.equal(out[key][:, unchanged], batch[key][:, unchanged])
    # An exposure scale only: radiance and references x s, variances x s^2, the rest as is, the
    # same s for both frames.
    out = augment(batch, torch.Generator().manual_seed(2), exposure_stops=2.0, permute=False)
    s = out["ref"][:, 0] / batch["ref"][:, 0]
    assert s.min() < 0.8 and s.max() > 1.25 and s.min() >= 0.25 and s.max() <= 4.0
    for key in ("raw", "raw_prev"):
        ratio = out[key] / batch[key]
        for c in range(29):
            power = 1 if c < 24 and c % 4 != 3 else 2 if c < 24 else 0
            torch.testing.assert_close(ratio[:, c], s ** power)
    torch.testing.assert_close(out["ref_prev"] / batch["ref_prev"], s[:, None].expand(n, 3))


def test_the_known_answer_reads_back(trained, tmp_path):
    model, _, _, _ = trained
    weights = export.export_model(model, tmp_path / "w.txt", "known answer")
    path = tmp_path / "known.txt"
    gaps = infer.known_answer(weights, path)
    assert gaps["features_gap"] < 1e-4 and gaps["output_gap"] < 1e-4
    inputs, feats, outputs = infer.read_known_answer(path)
    assert inputs.shape == (48, 29) and feats.shape == (48, 14) and outputs.shape == (48, 3)
    np.testing.assert_array_equal(inputs, infer.known_answer_inputs())
    np.testing.assert_array_equal(feats, features(torch.from_numpy(inputs)).numpy())
    np.testing.assert_array_equal(outputs, infer.run(weights, inputs))
    assert inputs[0, 28] == 0 and np.array_equal(outputs[0], inputs[0, 25:28] * inputs[0, 0:3])


def test_the_committed_known_answer_matches_its_weights():
    path = SOURCE_DIR / "tests" / "data" / "learned_known_answer.txt"
    if not path.is_file():
        pytest.skip(f"{path} not written yet")
    header = [line for line in path.read_text().splitlines() if line.startswith("#")]
    name = next(line for line in header if "Weights:" in line).split("Weights: ")[1].split()[0]
    inputs, feats, outputs = infer.read_known_answer(path)
    np.testing.assert_array_equal(feats, features(torch.from_numpy(inputs)).numpy())
    np.testing.assert_allclose(outputs, infer.run(path.parent / name, inputs), rtol=1e-6,
                               atol=1e-7)


def test_the_exported_file_loads_and_runs_in_the_library(trained, tmp_path, plane):
    """The C++ library reads the exported weights (the learned method denoises with them) and
    refuses a truncated copy, naming the file."""
    import rtdenoise

    model = trained[0]
    path = export.export_model(model, tmp_path / "w.txt", "the smoke test's synthetic run")
    rng = np.random.default_rng(2)
    color = rng.exponential(0.5, (plane.height, plane.width, 3)).astype(np.float32)
    den = rtdenoise.Denoiser("learned", device="cpu", weights=path)
    out = den.denoise(**plane.inputs(color))
    assert out.shape == color.shape and np.isfinite(out).all()
    assert 0.5 * color.mean() < out.mean() < 2.0 * color.mean()
    damaged = tmp_path / "truncated.txt"
    damaged.write_bytes(path.read_bytes()[:-40])
    with pytest.raises(rtdenoise.Error, match="truncated.txt"):
        rtdenoise.Denoiser("learned", device="cpu", weights=damaged)
