"""rtdenoise.compare and rtdenoise.metrics: known answers and the command's numbers."""

import json
import math

import numpy as np
import pytest

import rtdenoise
from conftest import run_cli


def images(count=3, seed=6, shape=(24, 32, 3)):
    rng = np.random.default_rng(seed)
    return [rng.uniform(0, 2, shape).astype(np.float32) for _ in range(count)]


def test_identical_sequences_score_perfectly():
    frames = images()
    comparison = rtdenoise.compare(frames, frames)
    assert len(comparison.frames) == 3
    for i, m in enumerate(comparison.frames):
        assert m.mse == 0 and m.relmse == 0 and m.ssim == pytest.approx(1, abs=1e-12)
        assert math.isinf(m.psnr)
        assert m.temporal_error is None if i == 0 else m.temporal_error == 0
    assert comparison.mean.mse == 0 and comparison.mean.temporal_error == 0


def test_a_known_offset_gives_its_mse():
    reference = images(count=1)[0]
    result = reference + np.float32(0.1)
    comparison = rtdenoise.compare([result] * 3, [reference] * 3)
    expected_relmse = np.mean(
        (result.astype(np.float64) - reference) ** 2 / (reference.astype(np.float64) ** 2 + 0.01)
    )
    for m in comparison.frames:
        assert m.mse == pytest.approx(0.01, rel=1e-5)
        assert m.relmse == pytest.approx(expected_relmse, rel=1e-6)
        assert m.ssim < 1 and m.psnr < math.inf
    # The same images every frame: the result changes exactly as the reference does.
    assert comparison.frames[1].temporal_error == 0
    one = rtdenoise.metrics(result, reference)
    assert one.mse == comparison.frames[0].mse and one.temporal_error is None
    assert one.psnr == comparison.frames[0].psnr and one.ssim == comparison.frames[0].ssim


def test_matches_the_command_line_compare(cli, scene, cli_denoised, tmp_path):
    report = tmp_path / "quality.json"
    run_cli(cli, "compare", cli_denoised, scene / "reference", "--json", report)
    expected = json.loads(report.read_text())
    comparison = rtdenoise.compare(cli_denoised, scene / "reference")  # folders
    names = {"mse": "mse", "relmse": "rel_mse", "psnr": "psnr", "ssim": "ssim",
             "temporal_error": "temporal_error"}
    rows = list(zip(comparison.frames, expected["frames"])) + [(comparison.mean, expected["mean"])]
    assert len(rows) == 5
    for got, want in rows:
        for ours, theirs in names.items():  # the same code: the same doubles
            assert getattr(got, ours) == want[theirs], ours
        assert got.energy_ratio == pytest.approx(want["energy_ratio"], rel=1e-12)
    assert "mean" in comparison.table()


def test_arrays_of_frames_and_rgba_are_accepted():
    frames = images()
    stacked = np.stack([np.concatenate([f, np.ones_like(f[..., :1])], -1) for f in frames])
    comparison = rtdenoise.compare(stacked, frames, exposure=2.0)
    assert comparison.mean.mse == 0


def test_mismatches_are_refused():
    frames = images()
    with pytest.raises(rtdenoise.InvalidArgumentError, match="3 results but 2 references"):
        rtdenoise.compare(frames, frames[:2])
    with pytest.raises(rtdenoise.InvalidArgumentError, match="frame 0"):
        rtdenoise.compare(frames, images(shape=(8, 8, 3)))
    with pytest.raises(rtdenoise.InvalidArgumentError, match="exposure"):
        rtdenoise.metrics(frames[0], frames[0], exposure=0)
