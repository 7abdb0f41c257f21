"""rtdenoise.open_sequence, read_exr, write_exr."""

import numpy as np
import pytest

import rtdenoise
from conftest import BLENDER_FIXTURE, FRAMES, HEIGHT, WIDTH


def test_a_course_folder_reads_as_frames(scene):
    sequence = rtdenoise.open_sequence(scene)
    assert len(sequence) == FRAMES and "course layout" in sequence.description
    frame = sequence[-1]
    assert frame.shape == (HEIGHT, WIDTH)
    for name in ("color", "normal", "position", "albedo"):
        array = getattr(frame, name)
        assert array.shape == (HEIGHT, WIDTH, 3) and array.dtype == np.float32, name
    assert frame.depth.shape == (HEIGHT, WIDTH) and frame.depth.dtype == np.float32
    assert frame.ids.shape == (HEIGHT, WIDTH) and frame.ids.dtype == np.int32
    assert frame.motion is None and frame.depth_kind == "view-z"
    count = frame.matrices.object_to_world.shape[0]
    assert frame.matrices.object_to_world.shape == (count, 4, 4) and count == frame.object_count
    assert frame.matrices.world_to_screen.shape == (4, 4)
    assert frame.ids.min() >= -1 and frame.ids.max() < count
    # The arrays are the files' values.
    last = FRAMES - 1
    np.testing.assert_array_equal(frame.color, rtdenoise.read_exr(scene / f"beauty_{last}.exr"))
    depth_file = rtdenoise.read_exr(scene / f"depth_{last}.exr")
    np.testing.assert_array_equal(frame.depth[..., None], depth_file)
    # A point's view depth is row 3 of world_to_screen applied to its position.
    row = frame.matrices.world_to_screen[3]
    w = frame.position @ row[:3] + row[3]
    mask = frame.ids >= 0
    np.testing.assert_allclose(w[mask], frame.depth[mask], rtol=1e-4)
    assert len(sequence[1:3]) == 2
    with pytest.raises(IndexError):
        sequence[FRAMES]


def test_blender_files_read_with_motion_vectors():
    sequence = rtdenoise.open_sequence(BLENDER_FIXTURE / "noisy")
    frame = sequence[0]
    assert len(sequence) == 4 and frame.matrices is None
    assert frame.motion.shape == (48, 64, 2) and frame.object_count == 4
    assert str(sequence.frame_file(0)).endswith("0001.exr")


def test_a_missing_folder_raises_missing_file(tmp_path):
    with pytest.raises(rtdenoise.MissingFileError) as caught:
        rtdenoise.open_sequence(tmp_path / "nothing")
    assert caught.value.code == rtdenoise.ErrorCode.MISSING_FILE
    assert "nothing" in str(caught.value) and isinstance(caught.value, FileNotFoundError)


def test_exr_round_trips(tmp_path):
    rng = np.random.default_rng(5)
    rgb = rng.uniform(-2, 40, (7, 5, 3)).astype(np.float32)
    rtdenoise.write_exr(tmp_path / "rgb.exr", rgb)
    np.testing.assert_array_equal(rtdenoise.read_exr(tmp_path / "rgb.exr"), rgb)
    rtdenoise.write_exr(tmp_path / "zip.exr", rgb.astype(np.float64), compression="zip")
    np.testing.assert_array_equal(rtdenoise.read_exr(tmp_path / "zip.exr"), rgb)
    rtdenoise.write_exr(tmp_path / "half.exr", rgb, half=True)
    np.testing.assert_array_equal(
        rtdenoise.read_exr(tmp_path / "half.exr"), rgb.astype(np.float16).astype(np.float32)
    )
    grey = rgb[..., 0]
    rtdenoise.write_exr(tmp_path / "y.exr", grey)
    np.testing.assert_array_equal(rtdenoise.read_exr(tmp_path / "y.exr"), grey[..., None])
    rgba = rng.uniform(0, 1, (7, 5, 4)).astype(np.float32)
    rtdenoise.write_exr(tmp_path / "rgba.exr", rgba)
    np.testing.assert_array_equal(
        rtdenoise.read_exr(tmp_path / "rgba.exr", channels=["R", "G", "B", "A"]), rgba
    )


def test_exr_errors_name_the_problem(tmp_path):
    with pytest.raises(rtdenoise.InvalidArgumentError, match=r"shape \(3,\)"):
        rtdenoise.write_exr(tmp_path / "bad.exr", np.zeros(3))
    with pytest.raises(rtdenoise.InvalidArgumentError, match="fast"):
        rtdenoise.write_exr(tmp_path / "bad.exr", np.zeros((2, 2, 3)), compression="fast")
    with pytest.raises(rtdenoise.Error, match="missing.exr"):
        rtdenoise.read_exr(tmp_path / "missing.exr")
