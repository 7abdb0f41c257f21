"""Issue 40: a chunk of a sequence through Python (denoise_chunk) gives the command's
`--frames A:B` results, with the input's frame numbers."""

import numpy as np
import pytest

import rtdenoise
from conftest import BLENDER_FIXTURE, run_cli


def test_a_chunk_matches_the_commands_chunk(cli, tmp_path):
    sequence = rtdenoise.open_sequence(BLENDER_FIXTURE / "noisy")
    assert sequence.first_number == 1  # 0001.exr
    out = tmp_path / "out"
    run_cli(cli, "denoise", BLENDER_FIXTURE / "noisy", "-o", out, "--method", "svgf",
            "--device", "cpu", "-q", "--frames", "3:5", "--warmup", "1")
    den = rtdenoise.Denoiser("svgf", device="cpu")
    chunk = list(rtdenoise.denoise_chunk(den, sequence, 3, 5, warmup=1))
    assert [number for number, _ in chunk] == [3, 4]
    for number, image in chunk:
        np.testing.assert_allclose(image, rtdenoise.read_exr(out / f"result_{number}.exr"),
                                   rtol=0, atol=1e-6)
    assert rtdenoise.DEFAULT_CHUNK_WARMUP >= 1


def test_a_chunk_outside_the_sequence_names_its_frames():
    sequence = rtdenoise.open_sequence(BLENDER_FIXTURE / "noisy")
    den = rtdenoise.Denoiser("svgf", device="cpu")
    with pytest.raises(rtdenoise.InvalidArgumentError, match=r"frames 4\.\.5 reach outside .*frames 1\.\.4"):
        next(rtdenoise.denoise_chunk(den, sequence, 4, 6))
