"""examples/python/denoise_scene.py runs and prints the command's numbers."""

import os
import subprocess
import sys

import rtdenoise
from conftest import SOURCE_DIR


def test_denoise_scene_example(scene, cli_denoised):
    completed = subprocess.run(
        [sys.executable, str(SOURCE_DIR / "examples" / "python" / "denoise_scene.py"), str(scene),
         "--device", "cpu"],
        capture_output=True, text=True, timeout=120, env=dict(os.environ),
    )
    assert completed.returncode == 0, completed.stderr
    lines = completed.stdout.splitlines()
    assert lines[1].split() == [
        "frame", "MSE", "relMSE", "PSNR", "(dB)", "SSIM", "temporal", "energy"
    ]
    # svgf with its defaults: the command's results, so the command's table.
    expected = rtdenoise.compare(cli_denoised, scene / "reference")
    assert lines[2:-1] == expected.table().splitlines()[1:]
