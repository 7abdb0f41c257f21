"""rtdenoise.Denoiser: known answers, the command line's results, layouts, history, errors."""

import warnings

import numpy as np
import pytest

import rtdenoise
from conftest import BLENDER_FIXTURE, Plane, max_relative_difference, rel_mse

METHODS = ["jbf", "atrous", "temporal", "svgf", "detail"]


def cuda_available():
    try:
        rtdenoise.Denoiser("svgf", device="cuda")
    except rtdenoise.Error:
        return False
    return True


# ---- known answers ----


@pytest.mark.parametrize("method", METHODS)
def test_constant_colour_on_a_flat_plane_stays_constant(method, plane):
    colour = np.array([0.25, 0.5, 0.75], np.float32)
    den = rtdenoise.Denoiser(method, device="cpu")
    for _ in range(3):  # the temporal methods blend in their history too
        result = den.denoise(**plane.inputs(np.broadcast_to(colour, plane.depth.shape + (3,))))
        assert result.shape == (plane.height, plane.width, 3) and result.dtype == np.float32
        assert np.max(np.abs(result - colour)) < 1e-4


def test_depth_and_position_are_computed_from_each_other(plane):
    screen = plane.world_to_screen
    depth = rtdenoise._depth_from_position(plane.position, screen, "view-z")
    np.testing.assert_allclose(depth, plane.depth, rtol=1e-6)
    position = rtdenoise._position_from_depth(plane.depth, screen, "view-z")
    np.testing.assert_allclose(position, plane.position, atol=1e-5)
    # Ray distance: |p - camera|, the camera at the origin.
    distance = np.linalg.norm(plane.position, axis=-1)
    np.testing.assert_allclose(
        rtdenoise._depth_from_position(plane.position, screen, "ray-distance"), distance, rtol=1e-6
    )
    np.testing.assert_allclose(
        rtdenoise._position_from_depth(distance, screen, "ray-distance"), plane.position, atol=1e-5
    )


def test_depth_or_position_alone_with_matrices_gives_the_full_result(plane):
    rng = np.random.default_rng(1)
    color = rng.uniform(0, 1, plane.depth.shape + (3,)).astype(np.float32)
    both = rtdenoise.Denoiser("svgf", device="cpu").denoise(**plane.inputs(color))
    inputs = plane.inputs(color)
    del inputs["depth"]
    from_position = rtdenoise.Denoiser("svgf", device="cpu").denoise(**inputs)
    np.testing.assert_array_equal(from_position, both)  # the depth is 5 exactly
    inputs = plane.inputs(color)
    del inputs["position"]
    from_depth = rtdenoise.Denoiser("svgf", device="cpu").denoise(**inputs)
    assert max_relative_difference(from_depth, both) < 1e-4


# ---- the command line's results ----


def test_matches_the_command_line_on_a_rendered_scene(scene, cli_denoised):
    sequence = rtdenoise.open_sequence(scene)
    assert len(sequence) == 4
    den = rtdenoise.Denoiser(device="cpu")
    for i, frame in enumerate(sequence):
        result = den.denoise_frame(frame)
        expected = rtdenoise.read_exr(cli_denoised / f"result_{i}.exr")
        assert max_relative_difference(result, expected) <= 1e-6, f"frame {i}"


def test_matches_the_command_line_on_blender_motion_vectors(cli_denoised_blender):
    sequence = rtdenoise.open_sequence(BLENDER_FIXTURE / "noisy")
    den = rtdenoise.Denoiser(device="cpu")
    for i, frame in enumerate(sequence):
        assert frame.matrices is None and frame.motion is not None
        result = den.denoise_frame(frame)
        expected = rtdenoise.read_exr(cli_denoised_blender / f"result_{i}.exr")
        assert max_relative_difference(result, expected) <= 1e-6, f"frame {i}"


# ---- layouts: strides, float16, float64, out= ----


def denoise_sequence(frames, method=None, transform=lambda inputs: inputs, out=None):
    den = rtdenoise.Denoiser(method, device="cpu")
    return [den.denoise(**transform(f.inputs()), out=out).copy() for f in frames]


def padded(array, extra_channels, fill=7.0, dtype=None):
    """`array`'s values inside a wider array (an RGBA buffer): a strided view of it."""
    array = array[..., None] if array.ndim == 2 else array
    dtype = dtype or array.dtype
    wide = np.full(array.shape[:2] + (array.shape[2] + extra_channels,), fill, dtype)
    wide[..., : array.shape[2]] = array
    view = wide[..., : array.shape[2]]
    return view[..., 0] if view.shape[2] == 1 else view


@pytest.fixture(scope="module")
def frames(scene):
    return list(rtdenoise.open_sequence(scene))


@pytest.fixture(scope="module")
def reference_results(frames):
    return denoise_sequence(frames)


def test_strided_views_are_read_in_place_and_give_the_same_result(frames, reference_results):
    frame = frames[0]
    rgba = padded(frame.color, 1)
    binding = rtdenoise._Binding(rgba, 3)
    # The array bound is the caller's view itself: no copy, its 16-byte pixel stride passed on.
    assert binding.array is rgba and not binding.copied
    assert (binding.format, binding.pixel_stride) == (rtdenoise._native.FORMAT_FLOAT + 2, 16)
    assert binding.row_stride == 16 * frame.color.shape[1]

    def strided(inputs):
        for name in ("color", "normal", "position"):
            inputs[name] = padded(inputs[name], 1)
        inputs["depth"] = padded(inputs["depth"], 3)
        inputs["ids"] = padded(inputs["ids"], 1, fill=-7)
        return inputs

    for got, expected in zip(denoise_sequence(frames, transform=strided), reference_results):
        np.testing.assert_array_equal(got, expected)


def test_in_place_inputs_allocate_nothing_but_the_output(frames):
    """numpy reports its buffers to tracemalloc: a frame of strided float32 views allocates the
    output alone, one with float64 inputs a float32 copy of each as well."""
    import tracemalloc

    def peak_bytes(den, inputs):
        tracemalloc.start()
        try:
            den.denoise(**inputs)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    inputs = frames[0].inputs()
    for name in ("color", "normal", "position"):
        inputs[name] = padded(inputs[name], 1)
    den = rtdenoise.Denoiser(device="cpu")
    den.denoise(**inputs)  # the first frame allocates the library's buffers (not numpy's)
    output_bytes = frames[0].color.nbytes
    assert output_bytes <= peak_bytes(den, inputs) < output_bytes + 16384
    inputs["color"] = inputs["color"].astype(np.float64)
    inputs["normal"] = inputs["normal"].astype(np.float64)
    assert peak_bytes(den, inputs) >= 3 * output_bytes


def test_rgba_arrays_give_the_rgb_result(frames, reference_results):
    def rgba(inputs):
        for name in ("color", "normal", "position"):
            inputs[name] = np.ascontiguousarray(padded(inputs[name], 1).base)
        return inputs

    assert rtdenoise._Binding(np.zeros((2, 2, 4), np.float32), 4).format == 4  # FLOAT4
    for got, expected in zip(denoise_sequence(frames, transform=rgba), reference_results):
        np.testing.assert_array_equal(got, expected)


def test_float64_and_non_contiguous_inputs_are_converted(frames, reference_results):
    def converted(inputs):
        inputs["color"] = inputs["color"].astype(np.float64)
        # Channels not contiguous (BGR reversed): a float32 copy is made.
        inputs["normal"] = np.ascontiguousarray(inputs["normal"][..., ::-1])[..., ::-1]
        inputs["position"] = np.asfortranarray(inputs["position"])
        inputs["ids"] = inputs["ids"].astype(np.int64)
        return inputs

    assert rtdenoise._Binding(np.zeros((2, 3, 3)), 3).copied  # float64
    assert rtdenoise._Binding(np.zeros((2, 3, 3), np.float32)[::-1], 3).copied  # negative rows
    assert rtdenoise._Binding(np.zeros((2, 3, 3), np.float32)[..., ::-1], 3).copied
    for got, expected in zip(denoise_sequence(frames, transform=converted), reference_results):
        np.testing.assert_array_equal(got, expected)


def test_float16_inputs_give_nearly_the_float32_result(frames, reference_results):
    def half(inputs):
        for name in ("color", "normal"):
            inputs[name] = inputs[name].astype(np.float16)
        return inputs

    assert rtdenoise._Binding(np.zeros((2, 2, 3), np.float16), 3).format == 7  # HALF3, in place
    assert not rtdenoise._Binding(np.zeros((2, 2, 3), np.float16), 3).copied
    for got, expected in zip(denoise_sequence(frames, transform=half), reference_results):
        assert not np.array_equal(got, expected)  # the half values were read
        assert rel_mse(got, expected) < 1e-3


def float64_with(value32, value64, name="color", method="jbf"):
    """The results of the plane's frame with pixel (10, 20)'s `name` set to value32 in float32
    and to value64 in float64 (the rest alike): the same when the float64 value is read as the
    float32 one."""
    plane = Plane()
    rng = np.random.default_rng(6)
    base = dict(color=rng.uniform(0.2, 1, plane.depth.shape + (3,)))
    if name != "color":
        base[name] = np.full(plane.depth.shape + (3,), 0.5)
    if name == "specular":
        base["roughness"] = np.full(plane.depth.shape, 0.1, np.float32)
    results = []
    for value, dtype in ((value32, np.float32), (value64, np.float64)):
        inputs = dict(plane.inputs(None), **{k: v.astype(dtype) for k, v in base.items()})
        inputs[name][10, 20] = value
        results.append(rtdenoise.Denoiser(method, device="cpu").denoise(**inputs))
    return results


@pytest.mark.parametrize(
    "name, method", [("color", "jbf"), ("color", "svgf"), ("albedo", "jbf"), ("specular", "detail")]
)
def test_float64_radiance_beyond_float32s_range_is_clamped_as_documented(name, method):
    """1e300 is beyond float32: cast, it would be Inf, replaced by 0 (a black pixel); the
    library's clamp to +-1e16 (kMaxRadiance) applies instead, as to a float32 1e16."""
    clamped, wide = float64_with([1e16, 0.5, -1e16], [1e300, 0.5, -1e300], name, method)
    assert np.all(np.isfinite(wide))
    np.testing.assert_array_equal(wide, clamped)
    # NaN and Inf stay non-finite through the cast: replaced by 0 as in float32.
    non_finite = [np.nan, np.inf, -np.inf]
    replaced, wide = float64_with(non_finite, non_finite, name, method)
    np.testing.assert_array_equal(wide, replaced)


def test_out_arrays_are_written_in_place(frames, reference_results):
    frame = frames[0]
    den = rtdenoise.Denoiser(device="cpu")
    rgba = np.full(frame.shape + (4,), 0.25, np.float32)
    result = den.denoise_frame(frame, out=rgba[..., :3])  # keeps the caller's alpha
    assert result.base is rgba
    np.testing.assert_array_equal(rgba[..., :3], reference_results[0])
    assert np.all(rgba[..., 3] == 0.25)

    half4 = np.zeros(frame.shape + (4,), np.float16)
    den.reset()
    assert den.denoise_frame(frame, out=half4) is half4
    np.testing.assert_array_equal(half4[..., 3], 1.0)
    np.testing.assert_allclose(half4[..., :3], reference_results[0], rtol=1e-3, atol=1e-4)

    wide = np.zeros(frame.shape + (3,), np.float64)  # another dtype: written through a copy
    den.reset()
    assert den.denoise_frame(frame, out=wide) is wide
    np.testing.assert_array_equal(wide, reference_results[0])


# ---- history ----


@pytest.mark.parametrize("method", ["temporal", "svgf", "detail"])
def test_history_is_kept_across_calls_and_reset_forgets_it(frames, method):
    den = rtdenoise.Denoiser(method, device="cpu")
    frame = frames[1]
    first = den.denoise_frame(frame)
    second = den.denoise_frame(frame)
    assert not np.array_equal(first, second)
    den.reset()
    np.testing.assert_array_equal(den.denoise_frame(frame), first)



def test_setting_a_value_again_before_every_frame_keeps_the_history(frames, reference_results):
    """An engine that sets its parameters before every frame still gets temporal filtering: the
    results are the plain run's; a new sigma takes effect over the kept history."""
    den = rtdenoise.Denoiser(device="cpu")
    for frame, expected in zip(frames, reference_results):
        den.set("sigma_color", 0.6)
        den.set("detail_sigma_luminance", den.get("detail_sigma_luminance"))
        np.testing.assert_array_equal(den.denoise_frame(frame), expected)
    changed = den.denoise_frame(frames[0])
    den.set("detail_sigma_luminance", 1.0)
    after = den.denoise_frame(frames[1])
    fresh = rtdenoise.Denoiser(device="cpu", detail_sigma_luminance=1.0).denoise_frame(frames[1])
    assert not np.array_equal(after, fresh) and not np.array_equal(after, changed)

def test_zero_confidence_drops_the_detail_methods_history(frames):
    den = rtdenoise.Denoiser("detail", device="cpu")
    den.denoise_frame(frames[0])
    inputs = frames[1].inputs()
    inputs.pop("confidence")
    height, width = inputs["color"].shape[:2]
    dropped = den.denoise(**inputs, confidence=np.zeros((height, width), np.float32)).copy()
    fresh = rtdenoise.Denoiser("detail", device="cpu").denoise(**inputs)
    np.testing.assert_allclose(dropped, fresh, rtol=1e-5, atol=1e-6)
    kept = rtdenoise.Denoiser("detail", device="cpu")
    kept.denoise_frame(frames[0])
    continued = kept.denoise(**inputs, confidence=np.ones((height, width), np.float32))
    assert np.abs(continued - fresh).max() > 1e-3


def split_signal(inputs, hit_distance=True):
    """The split signal for a frame's inputs: a quarter of its colour as specular."""
    height, width = inputs["color"].shape[:2]
    rng = np.random.default_rng(4)
    signal = dict(
        specular=(0.25 * inputs["color"][..., :3]).astype(np.float32),
        roughness=rng.uniform(0, 1, (height, width)).astype(np.float32),
    )
    if hit_distance:
        signal["hit_distance"] = rng.uniform(0, 5, (height, width)).astype(np.float32)
    return signal


@pytest.mark.parametrize("hit_distance", [True, False])
def test_the_split_signal_is_taken_by_detail(frames, hit_distance):
    den = rtdenoise.Denoiser("detail", device="cpu")
    for frame in frames[:2]:
        inputs = frame.inputs()
        for name in ("specular", "roughness", "hit_distance"):
            assert inputs.pop(name) is None  # the scene is rendered without it
        result = den.denoise(**inputs, **split_signal(inputs, hit_distance))
        assert result.shape == inputs["color"].shape[:2] + (3,)
        assert np.all(np.isfinite(result))
    # Half roughness, RGBA specular.
    signal = split_signal(inputs, hit_distance)
    signal["roughness"] = signal["roughness"].astype(np.float16)
    signal["specular"] = np.concatenate(
        [signal["specular"], np.ones(signal["specular"].shape[:2] + (1,), np.float32)], axis=-1
    )
    assert np.all(np.isfinite(den.denoise(**inputs, **signal)))


def test_the_split_signal_needs_its_partner(frames):
    den = rtdenoise.Denoiser("detail", device="cpu")
    inputs = frames[0].inputs()
    signal = split_signal(inputs)
    for name in ("specular", "roughness", "hit_distance"):
        inputs.pop(name)
    error = error_of(den.denoise, **inputs, roughness=signal["roughness"])
    assert "roughness is given without specular" in str(error)
    assert error.code == rtdenoise.ErrorCode.INVALID_INPUT
    error = error_of(den.denoise, **inputs, hit_distance=signal["hit_distance"])
    assert "hit_distance" in str(error) or "hitDistance" in str(error)
    error = error_of(den.denoise, **inputs, specular=signal["specular"])
    assert "specular is given without roughness" in str(error)
    error = error_of(den.denoise, **inputs, **dict(signal, roughness=signal["roughness"][:-1]))
    assert "roughness" in str(error) and error.code == rtdenoise.ErrorCode.INVALID_ARGUMENT
    assert np.all(np.isfinite(den.denoise(**inputs, **signal)))  # still usable


def test_the_split_signal_is_read_from_a_sequence(scene, tmp_path):
    import shutil

    folder = tmp_path / "split"
    shutil.copytree(scene, folder)
    frame = rtdenoise.open_sequence(folder)[0]
    height, width = frame.shape
    specular = np.full((height, width, 3), 0.125, np.float32)
    rtdenoise.write_exr(folder / "specular_0.exr", specular)
    rtdenoise.write_exr(folder / "roughness_0.exr", np.full((height, width), 0.5, np.float32))
    rtdenoise.write_exr(folder / "hit_distance_0.exr", np.full((height, width), 3.0, np.float32))
    frame = rtdenoise.open_sequence(folder)[0]
    np.testing.assert_array_equal(frame.specular, specular)
    assert frame.roughness.shape == (height, width) and np.all(frame.roughness == 0.5)
    assert frame.hit_distance.shape == (height, width) and np.all(frame.hit_distance == 3.0)
    assert rtdenoise.open_sequence(folder)[1].specular is None
    result = rtdenoise.Denoiser("detail", device="cpu").denoise_frame(frame)
    assert np.all(np.isfinite(result))


def test_single_frame_methods_need_no_matrices(plane):
    color = np.random.default_rng(2).uniform(0, 1, plane.depth.shape + (3,)).astype(np.float32)
    inputs = plane.inputs(color)
    with_matrices = rtdenoise.Denoiser("atrous", device="cpu").denoise(**inputs)
    del inputs["matrices"]
    without = rtdenoise.Denoiser("atrous", device="cpu").denoise(**inputs)
    np.testing.assert_array_equal(without, with_matrices)


def test_object_count_bounds_the_ids_after_frames_with_matrices(plane):
    """A single-frame method given matrices on one frame and none on the next: the next frame's
    object count bounds its IDs, not the earlier matrices' count (1)."""
    color = np.random.default_rng(8).uniform(0, 1, plane.depth.shape + (3,)).astype(np.float32)
    inputs = plane.inputs(color)
    den = rtdenoise.Denoiser("jbf", device="cpu")
    den.denoise(**inputs)
    del inputs["matrices"]
    inputs["ids"] = np.where(np.arange(plane.width) < 32, 0, 3).astype(np.int32)[None].repeat(
        plane.height, 0
    )
    expected = rtdenoise.Denoiser("jbf", device="cpu").denoise(**inputs)
    np.testing.assert_array_equal(den.denoise(**inputs), expected)
    np.testing.assert_array_equal(den.denoise(**inputs, object_count=4), expected)
    error = error_of(den.denoise, **inputs, object_count=3)
    assert error.code == rtdenoise.ErrorCode.INVALID_INPUT and "3" in str(error)


def test_ids_default_to_one_object_with_background_where_the_normal_is_zero(plane):
    color = np.random.default_rng(3).uniform(0, 1, plane.depth.shape + (3,)).astype(np.float32)
    plane.normal[:10] = 0
    inputs = plane.inputs(color)
    explicit = plane.ids.copy()
    explicit[:10] = -1
    inputs["ids"] = explicit
    expected = rtdenoise.Denoiser("svgf", device="cpu").denoise(**inputs)
    del inputs["ids"]
    got = rtdenoise.Denoiser("svgf", device="cpu").denoise(**inputs)
    np.testing.assert_array_equal(got, expected)
    np.testing.assert_array_equal(got[:10], color[:10])  # background passes through



@pytest.mark.parametrize("broken", ["ids", "depth", "normal"])
def test_a_frame_without_usable_geometry_is_warned_of(plane, broken):
    """Every ID -1, a depth of NaN, or zero normals everywhere: the frame comes back (nearly) as
    noisy as it went in, so a RuntimeWarning names what broke; a normal frame warns of nothing."""
    color = np.random.default_rng(5).uniform(0, 1, plane.depth.shape + (3,)).astype(np.float32)
    inputs = plane.inputs(color)
    den = rtdenoise.Denoiser("svgf", device="cpu")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        den.denoise(**inputs)
    expected = {"ids": "background", "depth": "NaN or Inf depth", "normal": "zero or non-finite normal"}
    if broken == "ids":
        inputs["ids"] = np.full_like(plane.ids, -1)
    elif broken == "depth":
        inputs["depth"] = np.full_like(plane.depth, np.nan)
        del inputs["position"]
    else:
        inputs["normal"] = np.zeros_like(plane.normal)
    with pytest.warns(RuntimeWarning, match=expected[broken]):
        den.denoise(**inputs)

# ---- settings ----


def test_settings_by_keyword_and_by_name():
    den = rtdenoise.Denoiser(
        "svgf", device="cpu", sigma_color=0.8, svgf_iterations=3, outlier=False,
        spatial_filter="jbf", motion_scale=(2, -1), depth_kind="ray-distance",
    )
    assert den.get("sigma_color") == pytest.approx(0.8)
    assert den.get("sigma-color") == pytest.approx(0.8)
    assert den.get("svgf_iterations") == 3 and isinstance(den.get("svgf_iterations"), int)
    assert den.get("outlier") is False
    assert den.get("spatial_filter") == "jbf"
    assert den.get("motion_scale") == (2.0, -1.0)
    assert den.get("depth_kind") == "ray-distance"
    den.set("sigma_color", 1)  # an int sets a float setting
    assert den.get("sigma_color") == 1.0
    assert den.method == "svgf" and den.device_name.startswith("cpu")
    assert rtdenoise.__version__.count(".") == 2


# ---- errors ----


def error_of(call, *args, **kwargs):
    with pytest.raises(rtdenoise.Error) as caught:
        call(*args, **kwargs)
    return caught.value


def test_unknown_setting_name():
    error = error_of(rtdenoise.Denoiser, "svgf", device="cpu", sigma_colour=0.5)
    assert "sigma-colour" in str(error) and error.code == rtdenoise.ErrorCode.INVALID_ARGUMENT
    assert isinstance(error, ValueError) and isinstance(error, RuntimeError)
    assert "sigma-colour" in str(error_of(rtdenoise.Denoiser(device="cpu").get, "sigma_colour"))


def test_value_out_of_range_or_of_the_wrong_type():
    den = rtdenoise.Denoiser(device="cpu")
    error = error_of(den.set, "radius", 100)
    assert "radius" in str(error) and error.code == rtdenoise.ErrorCode.INVALID_ARGUMENT
    assert error_of(den.set, "svgf_alpha", 1.5).code == rtdenoise.ErrorCode.INVALID_ARGUMENT
    assert "spatial-filter" in str(error_of(den.set, "spatial_filter", "median"))
    assert "sigma-color" in str(error_of(den.set, "sigma_color", "big"))
    assert "sigma-color" in str(error_of(den.set, "sigma_color", [1]))


def test_wrong_shapes_are_named(plane):
    color = np.zeros(plane.depth.shape + (3,), np.float32)
    den = rtdenoise.Denoiser(device="cpu")
    inputs = plane.inputs(color)
    inputs["normal"] = np.zeros((4, 4, 3), np.float32)
    error = error_of(den.denoise, **inputs)
    assert str(error) == "normal: shape (4, 4, 3), expected (48, 64, 3 or 4) like color"
    inputs = plane.inputs(color)
    inputs["depth"] = np.zeros((48, 64, 2), np.float32)
    assert str(error_of(den.denoise, **inputs)).startswith("depth: shape (48, 64, 2)")
    inputs = plane.inputs(np.zeros((48, 64, 2), np.float32))
    assert str(error_of(den.denoise, **inputs)).startswith("color: shape (48, 64, 2)")
    inputs = plane.inputs(color)
    inputs["out"] = np.zeros((48, 64, 3), np.int32)
    assert "out: dtype int32" in str(error_of(den.denoise, **inputs))


def test_missing_depth_and_position(plane):
    color = np.zeros(plane.depth.shape + (3,), np.float32)
    den = rtdenoise.Denoiser(device="cpu")
    error = error_of(den.denoise, color, plane.normal, matrices=plane.matrices)
    assert "position and depth missing" in str(error)
    motion = np.zeros((48, 64, 2), np.float32)
    error = error_of(den.denoise, color, plane.normal, depth=plane.depth, motion=motion)
    assert "position missing" in str(error) and "matrices" in str(error)


def test_temporal_methods_need_motion_or_matrices(plane):
    inputs = plane.inputs(np.zeros(plane.depth.shape + (3,), np.float32))
    del inputs["matrices"]
    for method in ("temporal", "svgf", "detail"):
        den = rtdenoise.Denoiser(method, device="cpu")
        assert "motion or matrices" in str(error_of(den.denoise, **inputs)), method


def test_ids_out_of_range_are_refused_and_keep_the_history(plane):
    color = np.random.default_rng(4).uniform(0, 1, plane.depth.shape + (3,)).astype(np.float32)
    undisturbed = rtdenoise.Denoiser("svgf", device="cpu")
    undisturbed.denoise(**plane.inputs(color))
    expected = undisturbed.denoise(**plane.inputs(color))

    den = rtdenoise.Denoiser("svgf", device="cpu")
    den.denoise(**plane.inputs(color))
    inputs = plane.inputs(color)
    inputs["ids"] = np.full(plane.depth.shape, 3, np.int32)  # one object's matrix given
    error = error_of(den.denoise, **inputs)
    assert error.code == rtdenoise.ErrorCode.INVALID_INPUT and "3" in str(error)
    np.testing.assert_array_equal(den.denoise(**plane.inputs(color)), expected)


@pytest.mark.parametrize("motion", [False, True])
def test_an_object_count_beyond_int32_is_an_invalid_argument(plane, motion):
    inputs = plane.inputs(np.zeros(plane.depth.shape + (3,), np.float32))
    del inputs["matrices"]
    if motion:
        inputs["motion"] = np.zeros(plane.depth.shape + (2,), np.float32)
    den = rtdenoise.Denoiser("svgf" if motion else "jbf", device="cpu")
    for count in (2**40, 2**31, -1):
        error = error_of(den.denoise, **inputs, object_count=count)
        assert isinstance(error, rtdenoise.InvalidArgumentError)
        assert str(error) == f"object_count: {count} is out of range 0..2147483647"
    assert "object_count" in str(error_of(den.denoise, **inputs, object_count=2.5))
    # An ID no object count can bound: named as such, not a TypeError.
    ids = np.zeros(plane.depth.shape, np.int64)
    ids[3, 4] = 2**31 - 1
    error = error_of(den.denoise, **dict(inputs, ids=ids))
    assert error.code == rtdenoise.ErrorCode.INVALID_INPUT and "2147483647" in str(error)
    assert np.all(np.isfinite(den.denoise(**inputs, object_count=1)))  # still usable


def test_copying_or_pickling_a_denoiser_is_refused(plane):
    """A copy would share the native denoiser, and with it one history, with the original: two
    sequences through the two would mix."""
    import copy
    import pickle

    den = rtdenoise.Denoiser("svgf", device="cpu")
    for refused in (copy.copy, copy.deepcopy, pickle.dumps):
        error = error_of(refused, den)
        assert error.code == rtdenoise.ErrorCode.INVALID_OPERATION
        assert "cannot be copied" in str(error), refused
    assert np.all(np.isfinite(den.denoise(**plane.inputs(np.ones(plane.depth.shape + (3,))))))


def test_bad_device_and_method_names():
    error = error_of(rtdenoise.Denoiser, "svgf", device="gpu")
    assert "'gpu'" in str(error) and isinstance(error, ValueError)
    error = error_of(rtdenoise.Denoiser, "median", device="cpu")
    assert "median" in str(error) and error.code == rtdenoise.ErrorCode.INVALID_ARGUMENT


@pytest.mark.skipif(cuda_available(), reason="a CUDA device is there")
def test_cuda_without_a_gpu_raises_unsupported_device():
    error = error_of(rtdenoise.Denoiser, "svgf", device="cuda")
    assert error.code == rtdenoise.ErrorCode.UNSUPPORTED_DEVICE and "cuda" in str(error)


@pytest.mark.skipif(not cuda_available(), reason="no CUDA device")
def test_cuda_gives_the_cpu_result(frames, reference_results):
    den = rtdenoise.Denoiser(device="cuda")  # the default method, as reference_results
    assert den.device_name.startswith("cuda")
    for frame, expected in zip(frames, reference_results):
        assert rel_mse(den.denoise_frame(frame), expected) < 1e-4


# ---- threads ----


def test_denoisers_in_threads_give_the_serial_results(frames, reference_results):
    import concurrent.futures

    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        runs = [pool.submit(denoise_sequence, frames) for _ in range(2)]
        for run in runs:
            for got, expected in zip(run.result(), reference_results):
                np.testing.assert_array_equal(got, expected)


def test_one_denoiser_is_refused_to_a_second_thread_and_after_close(frames):
    den = rtdenoise.Denoiser(device="cpu")
    with den._exclusive():  # as while another thread's denoise() runs
        error = error_of(den.denoise_frame, frames[0])
    assert error.code == rtdenoise.ErrorCode.INVALID_OPERATION and "thread" in str(error)
    with den:
        den.denoise_frame(frames[0])
    assert "closed" in str(error_of(den.denoise_frame, frames[0]))


def test_close_during_a_denoise_in_another_thread_waits_for_its_frame():
    """close() from another thread while denoise() runs: the frame in flight completes, the
    calls after it raise the closed error; never an AttributeError."""
    import threading

    plane = Plane(256, 256)
    inputs = plane.inputs(np.random.default_rng(7).uniform(0, 1, (256, 256, 3)).astype(np.float32))
    den = rtdenoise.Denoiser("atrous", device="cpu")
    results, failures = [], []

    def run():
        try:
            for _ in range(1000):
                results.append(den.denoise(**inputs))
        except Exception as error:  # noqa: BLE001 (the test reports what it was)
            failures.append(error)

    worker = threading.Thread(target=run)
    worker.start()
    while not den._lock.locked() and worker.is_alive():
        pass  # until a call is under way (it holds the lock through the filtering)
    den.close()
    worker.join(30)
    assert len(failures) == 1, failures
    assert isinstance(failures[0], rtdenoise.Error), repr(failures[0])
    assert failures[0].code == rtdenoise.ErrorCode.INVALID_OPERATION
    assert "closed" in str(failures[0])
    assert results and all(np.all(np.isfinite(r)) for r in results)
    assert repr(den) == "<rtdenoise.Denoiser atrous on closed>"


def test_close_inside_a_call_of_the_same_thread_is_refused_not_a_deadlock():
    den = rtdenoise.Denoiser("jbf", device="cpu")
    with den._exclusive():  # as inside a denoise() of this thread
        error = error_of(den.close)
    assert error.code == rtdenoise.ErrorCode.INVALID_OPERATION and "close" in str(error)
    den.close()


# ---- cost ----


def test_a_large_object_id_costs_no_memory_per_object():
    """Without matrices, one ID of 5,000,000 (the object count 5,000,001) must not build or copy
    5,000,001 identity matrices (320 MB each time) where the method reads none: a single-frame
    method, or motion vectors. Peak RSS in a fresh interpreter, so that no earlier test's peak
    hides the growth."""
    import os
    import subprocess
    import sys

    script = """
import resource, sys
import numpy as np
import rtdenoise
sys.path.insert(0, sys.argv[1])
from conftest import Plane
plane = Plane()
inputs = plane.inputs(np.full(plane.depth.shape + (3,), 0.5, np.float32))
del inputs["matrices"]
motion = dict(motion=np.zeros(plane.depth.shape + (2,), np.float32))
runs = [("jbf", {}), ("atrous", {}), ("svgf", motion), ("detail", motion)]
for method, extra in runs:  # the first frame allocates the method's buffers
    rtdenoise.Denoiser(method, device="cpu").denoise(**inputs, **extra)
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
large = plane.ids.copy()
large[0, 0] = 5_000_000
for method, extra in runs:
    den = rtdenoise.Denoiser(method, device="cpu")
    for _ in range(2):
        den.denoise(**dict(inputs, ids=large), **extra)
    den.denoise(**inputs, **extra, object_count=5_000_001)
print((resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024)
"""
    env = dict(os.environ, PYTHONPATH=os.path.dirname(os.path.dirname(rtdenoise.__file__)))
    completed = subprocess.run(
        [sys.executable, "-c", script, os.path.dirname(__file__)],
        capture_output=True, text=True, timeout=120, env=env,
    )
    assert completed.returncode == 0, completed.stderr
    growth_mb = float(completed.stdout)
    assert growth_mb < 64, f"peak RSS grew by {growth_mb:.0f} MB"
