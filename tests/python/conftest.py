"""Fixtures of the rtdenoise Python tests: scenes rendered and denoised by the command line
(RTDENOISE_CLI, set by CTest), and a synthetic flat plane with known depth and positions.

Run by CTest (python.<file>, one test per file), or by hand:
    PYTHONPATH=build/release/python RTDENOISE_CLI=build/release/rtdenoise \\
        /usr/bin/python3 -m pytest -q tests/python
"""

import os
import pathlib
import subprocess

import numpy as np
import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
BLENDER_FIXTURE = SOURCE_DIR / "tests" / "data" / "blender"

# Small enough for the fast tier: the render, the command's denoise and the tests in seconds.
WIDTH, HEIGHT, FRAMES = 64, 48, 4


def _cli_path():
    path = os.environ.get("RTDENOISE_CLI")
    return pathlib.Path(path) if path else None


@pytest.fixture(scope="session")
def cli():
    """The `rtdenoise` program (RTDENOISE_CLI)."""
    path = _cli_path()
    if path is None or not path.is_file():
        pytest.skip("RTDENOISE_CLI does not name the rtdenoise program (CTest sets it)")
    return path


def run_cli(cli, *args):
    completed = subprocess.run(
        [str(cli), *map(str, args)], capture_output=True, text=True, timeout=120
    )
    assert completed.returncode == 0, f"rtdenoise {' '.join(map(str, args))}: {completed.stderr}"
    return completed.stdout


@pytest.fixture(scope="session")
def scene(cli, tmp_path_factory):
    """moving-objects rendered in the course layout (matrices), with reference/reference_<i>."""
    folder = tmp_path_factory.mktemp("scene")
    run_cli(
        cli, "render", "moving-objects", "-o", folder, "--width", WIDTH, "--height", HEIGHT,
        "--frames", FRAMES, "--ref-spp", 16, "-q",
    )
    return folder


@pytest.fixture(scope="session")
def cli_denoised(cli, scene, tmp_path_factory):
    """The command's results (default method) for `scene` on the CPU: result_<i>.exr."""
    folder = tmp_path_factory.mktemp("cli_denoised")
    run_cli(cli, "denoise", scene, "-o", folder, "--device", "cpu", "-q")
    return folder


@pytest.fixture(scope="session")
def cli_denoised_blender(cli, tmp_path_factory):
    """The command's results (default method) for the Cycles fixture (motion vectors, no
    matrices)."""
    folder = tmp_path_factory.mktemp("cli_blender")
    run_cli(cli, "denoise", BLENDER_FIXTURE / "noisy", "-o", folder, "--device", "cpu", "-q")
    return folder


class Plane:
    """A camera at the origin looking along +z at the plane z = distance: the frame's view depth
    is `distance` everywhere, its positions and matrices are known in closed form."""

    def __init__(self, width=WIDTH, height=HEIGHT, distance=5.0, focal=40.0):
        self.width, self.height, self.distance = width, height, distance
        cx, cy = width / 2, height / 2
        # s = M (x, y, z, 1): s.x = f x + cx z, s.y = f y + cy z, s.w = z; pixel = s.xy / s.w.
        self.world_to_screen = np.array(
            [[focal, 0, cx, 0], [0, focal, cy, 0], [0, 0, 1, 0], [0, 0, 1, 0]], np.float32
        )
        px = np.arange(width) + 0.5
        py = np.arange(height) + 0.5
        x = (px[None, :] - cx) * distance / focal
        y = (py[:, None] - cy) * distance / focal
        self.position = np.stack(
            np.broadcast_arrays(x, y, np.full((1, 1), distance)), axis=-1
        ).astype(np.float32)
        self.depth = np.full((height, width), distance, np.float32)
        self.normal = np.zeros((height, width, 3), np.float32)
        self.normal[..., 2] = -1.0
        self.ids = np.zeros((height, width), np.int32)
        self.matrices = dict(
            object_to_world=np.eye(4, dtype=np.float32)[None],
            world_to_camera=np.eye(4, dtype=np.float32),
            world_to_screen=self.world_to_screen,
        )

    def inputs(self, color):
        return dict(
            color=color, normal=self.normal, position=self.position, depth=self.depth,
            ids=self.ids, matrices=self.matrices,
        )


@pytest.fixture
def plane():
    return Plane()


def rel_mse(a, b):
    return float(np.mean((a.astype(np.float64) - b) ** 2 / (np.asarray(b, np.float64) ** 2 + 0.01)))


def max_relative_difference(a, b):
    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-3)))
