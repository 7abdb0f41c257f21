"""rtdenoise: a real-time denoiser for path-traced frame sequences.

    import rtdenoise
    den = rtdenoise.Denoiser("svgf", device="cpu", sigma_color=0.6)
    for frame in rtdenoise.open_sequence("out/quickstart/scene"):
        image = den.denoise_frame(frame)           # (H, W, 3) float32, history kept

    den.denoise(color, normal, position=..., depth=..., ids=..., matrices=...)   # own buffers

The denoiser is the library's C API (rtdenoise.h) underneath: settings are the command line's
option names with underscores (``svgf_iterations=3`` is ``--svgf-iterations 3``). Arrays are
(height, width, channels), rows top to bottom; float32 and float16 ones (int32 IDs) are read in
place, whatever their strides, when each pixel's values are contiguous. Failures raise
rtdenoise.Error with the library's message and an ErrorCode.
"""

from __future__ import annotations

import collections.abc
import contextlib
import dataclasses
import numbers
import os
import re
import threading
import warnings
from typing import Any, Mapping, NoReturn, Optional, Sequence, Union

import numpy as np

from . import _rtdenoise as _native
from ._errors import Error, ErrorCode, InvalidArgumentError, MissingFileError

__all__ = [
    "Comparison",
    "Denoiser",
    "Error",
    "ErrorCode",
    "Frame",
    "FrameMetrics",
    "FrameSequence",
    "InvalidArgumentError",
    "Matrices",
    "MissingFileError",
    "DEFAULT_CHUNK_WARMUP",
    "compare",
    "denoise_chunk",
    "metrics",
    "open_sequence",
    "read_exr",
    "write_exr",
]


def _version_string(version: int) -> str:
    return f"{version // 10000}.{version // 100 % 100}.{version % 100}"


__version__ = _version_string(_native.version())

PathLike = Union[str, "os.PathLike[str]"]

_DEVICES = {
    "default": _native.DEVICE_DEFAULT,
    "auto": _native.DEVICE_DEFAULT,
    "cpu": _native.DEVICE_CPU,
    "cuda": _native.DEVICE_CUDA,
}
_TEMPORAL_METHODS = ("temporal", "svgf", "detail", "learned")
_INT32_MAX = 2**31 - 1
# The library clamps radiance and albedo beyond +-kMaxRadiance (1e16) to it.
_MAX_RADIANCE = float(_native.MAX_RADIANCE)


# ---- matrices and frames ----


@dataclasses.dataclass
class Matrices:
    """A frame's matrices, row-major on column vectors (s = M (x, y, z, 1)):
    object_to_world (K, 4, 4), object k's local-to-world; world_to_camera and world_to_screen
    (4, 4), (s.x / s.w, s.y / s.w) being the pixel, its centre at +0.5."""

    object_to_world: np.ndarray
    world_to_camera: np.ndarray
    world_to_screen: np.ndarray

    @classmethod
    def of(cls, value: Any) -> "Matrices":
        """From a Matrices, a mapping with those three keys, an object with those attributes,
        or a (object_to_world, world_to_camera, world_to_screen) tuple; as float32."""
        names = ("object_to_world", "world_to_camera", "world_to_screen")
        if isinstance(value, Mapping):
            missing = [n for n in names if n not in value]
            if missing:
                raise InvalidArgumentError(f"matrices: no {', '.join(missing)}")
            parts = [value[n] for n in names]
        elif all(hasattr(value, n) for n in names):
            parts = [getattr(value, n) for n in names]
        elif isinstance(value, (tuple, list)) and len(value) == 3:
            parts = list(value)
        else:
            raise InvalidArgumentError(
                "matrices: expected a mapping or object with object_to_world, world_to_camera "
                f"and world_to_screen, got {type(value).__name__}"
            )
        object_to_world = np.ascontiguousarray(parts[0], dtype=np.float32)
        if object_to_world.shape == (4, 4):
            object_to_world = object_to_world[None]
        if object_to_world.ndim != 3 or object_to_world.shape[1:] != (4, 4):
            raise InvalidArgumentError(
                f"matrices: object_to_world has shape {object_to_world.shape}, expected (K, 4, 4)"
            )
        single = []
        for name, part in zip(names[1:], parts[1:]):
            matrix = np.ascontiguousarray(part, dtype=np.float32)
            if matrix.shape != (4, 4):
                raise InvalidArgumentError(
                    f"matrices: {name} has shape {matrix.shape}, expected (4, 4)"
                )
            single.append(matrix)
        return cls(object_to_world, single[0], single[1])


@dataclasses.dataclass
class Frame:
    """One frame of a sequence read by open_sequence: its noisy colour and G-buffer as numpy
    arrays (float32; ids int32), and how its pixels moved (motion vectors or matrices)."""

    color: np.ndarray  # (H, W, 3) noisy linear radiance
    normal: np.ndarray  # (H, W, 3) world-space unit normal, (0, 0, 0) on background
    position: np.ndarray  # (H, W, 3) world-space position
    depth: np.ndarray  # (H, W), see depth_kind
    ids: np.ndarray  # (H, W) int32 object IDs, -1 on background
    albedo: Optional[np.ndarray] = None  # (H, W, 3)
    motion: Optional[np.ndarray] = None  # (H, W, 2 or 3) pixels: previous = current + motion
    confidence: Optional[np.ndarray] = None  # (H, W) history confidence in [0, 1]
    # The split signal (method "detail"): the specular part of color, its roughness, hit distance.
    specular: Optional[np.ndarray] = None  # (H, W, 3)
    roughness: Optional[np.ndarray] = None  # (H, W) in [0, 1], with specular
    hit_distance: Optional[np.ndarray] = None  # (H, W) world units (0: unknown), with specular
    matrices: Optional[Matrices] = None  # None for Blender's files (they have motion)
    depth_kind: str = "view-z"  # or "ray-distance"
    object_count: int = 0  # IDs are -1..object_count-1

    @property
    def shape(self) -> tuple:
        """(height, width)."""
        return self.color.shape[:2]

    def inputs(self) -> dict:
        """The keyword arguments of Denoiser.denoise for this frame."""
        return dict(
            color=self.color,
            normal=self.normal,
            position=self.position,
            depth=self.depth,
            ids=self.ids,
            albedo=self.albedo,
            motion=self.motion,
            confidence=self.confidence,
            specular=self.specular,
            roughness=self.roughness,
            hit_distance=self.hit_distance,
            matrices=self.matrices,
            depth_kind=self.depth_kind,
            object_count=self.object_count,
        )


class FrameSequence(collections.abc.Sequence):
    """The frames of a sequence on disk (see open_sequence), read one at a time on access."""

    def __init__(self, path: PathLike, view_layer: Optional[str] = None):
        self.path = os.fspath(path)
        self._source = _native.FrameSource(self.path, view_layer or "")

    def __len__(self) -> int:
        return len(self._source)

    def __getitem__(self, index):
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        index = int(index)
        if index < 0:
            index += len(self)
        if not 0 <= index < len(self):
            raise IndexError(f"frame {index} out of range (the sequence holds {len(self)})")
        values = self._source.read_frame(index)
        matrices = values.pop("matrices")
        return Frame(matrices=Matrices(**matrices) if matrices else None, **values)

    @property
    def first_number(self) -> int:
        """The input's own number of frame 0 (beauty_<i>.exr's i: 0; Blender's 0001.exr: 1);
        frame i is number first_number + i."""
        return self._source.first_frame_number()

    def frame_file(self, index: int) -> str:
        """The file that stands for frame `index` in messages (its beauty or its EXR)."""
        return os.fspath(self._source.frame_file(index))

    @property
    def description(self) -> str:
        """The path and its layout ("... (course layout)")."""
        return self._source.describe()

    @property
    def warnings(self) -> list:
        """What the sequence lacks (an optional pass), one sentence each."""
        return list(self._source.warnings())

    @property
    def back_projection_problem(self) -> str:
        """Why its frames cannot be projected into the previous one ("" when they can)."""
        return self._source.back_projection_problem()

    def __repr__(self) -> str:
        return f"<rtdenoise.FrameSequence {self.description}, {len(self)} frames>"


# The warm-up `rtdenoise denoise --frames A:B` runs before a chunk when none is given: enough
# history for the chunk's first frame to match a run over the whole shot (docs/farm.md).
DEFAULT_CHUNK_WARMUP = int(_native.DEFAULT_CHUNK_WARMUP)


def denoise_chunk(denoiser, sequence: FrameSequence, first: int, end: int,
                  warmup: int = DEFAULT_CHUNK_WARMUP):
    """Denoises the chunk of `sequence` with the input's frame numbers first..end-1 (as
    `rtdenoise denoise --frames first:end --warmup warmup`): the `warmup` frames before `first`
    (fewer where the sequence starts sooner) are denoised for their history and not returned.
    Yields (frame number, (H, W, 3) float32 image) for the chunk's frames. InvalidArgumentError
    names the sequence and its frames for a range outside them. `denoiser` keeps its history:
    give a fresh one (or call reset()) per chunk."""
    warmup_index, first_index, end_index = sequence._source.chunk(int(first), int(end), int(warmup))
    for index in range(warmup_index, end_index):
        image = denoiser.denoise_frame(sequence[index])
        if index >= first_index:
            yield sequence.first_number + index, image


def open_sequence(path: PathLike, view_layer: Optional[str] = None) -> FrameSequence:
    """A sequence on disk, as `rtdenoise denoise` reads it: a folder in the course layout
    (beauty_i.exr, normal_i.exr, position_i.exr, depth_i.exr, ID_i.exr, matrix_i.mat, optional
    albedo_i.exr), or Blender's multilayer EXRs (their folder or a pattern such as
    "renders/shot_####.exr"; `view_layer`: the view layer to read, default the first).
    len() and indexing give Frames; Error (MissingFileError) names what is wrong."""
    return FrameSequence(path, view_layer)


# ---- EXR files ----


def read_exr(path: PathLike, channels: Optional[Sequence[str]] = None) -> np.ndarray:
    """An EXR's channels as an (H, W, C) float32 array: `channels` by name, or by default R, G,
    B (a one-channel file's channel; a Blender multilayer file's Combined colour)."""
    return _native.read_exr(os.fspath(path), None if channels is None else list(channels))


def write_exr(
    path: PathLike, array: Any, *, half: bool = False, compression: Optional[str] = None
) -> None:
    """Writes an (H, W) or (H, W, C) array as a linear EXR: channels Y (1), R G B (3), R G B A
    (4), FLOAT or with half=True HALF. compression: "none" (the default), "rle", "zips", "zip",
    "piz", "pxr24", "b44", "b44a", "dwaa", "dwab" (4-channel images: ZIP only). Written to a
    temporary name and renamed."""
    image = np.asarray(array)
    if image.ndim == 2:
        image = image[..., None]
    if image.ndim != 3 or image.shape[2] not in (1, 2, 3, 4):
        raise InvalidArgumentError(
            f"write_exr: shape {image.shape}, expected (H, W) or (H, W, 1 to 4)"
        )
    _native.write_exr(os.fspath(path), np.ascontiguousarray(image, np.float32), half, compression)


# ---- the denoiser ----


def _shape_text(shape: tuple) -> str:
    return "(" + ", ".join(str(s) for s in shape) + ")"


def _format_code(dtype: np.dtype, channels: int) -> Optional[int]:
    """The RTDFormat of `channels` values of `dtype` the C API reads in place, or None."""
    if not dtype.isnative:
        return None
    if dtype == np.float32:
        return _native.FORMAT_FLOAT + channels - 1
    if dtype == np.float16:
        return _native.FORMAT_HALF + channels - 1
    if dtype == np.int32 and channels == 1:
        return _native.FORMAT_INT
    return None


def _in_place_layout(array: np.ndarray, channels: int):
    """(format, pixel stride, row stride) to read `array` ((H, W) or (H, W, C)) where it lies,
    or None when the C API cannot: another dtype, a channel stride other than the value size,
    negative, zero (broadcast) or overlapping strides, unaligned data."""
    code = _format_code(array.dtype, channels)
    if code is None or not array.flags.aligned:
        return None
    height, width = array.shape[:2]
    itemsize = array.dtype.itemsize
    if array.ndim == 3 and array.shape[2] > 1 and array.strides[2] != itemsize:
        return None
    pixel_bytes = channels * itemsize
    # A stride along an axis of length 1 is never used: numpy may give it any value.
    pixel_stride = array.strides[1] if width > 1 else pixel_bytes
    row_stride = array.strides[0] if height > 1 else pixel_stride * width
    if pixel_stride < pixel_bytes or row_stride < pixel_stride * width:
        return None
    return code, pixel_stride, row_stride


class _Binding:
    """An image argument as the C API takes it: the array (the caller's, or a float32 copy),
    its format and strides."""

    def __init__(self, array: np.ndarray, channels: int):
        layout = _in_place_layout(array, channels)
        if layout is None:
            array = np.ascontiguousarray(array, dtype=np.float32)
            layout = (_native.FORMAT_FLOAT + channels - 1, 0, 0)
        self.array = array
        self.format, self.pixel_stride, self.row_stride = layout
        self.copied = layout[1] == 0


def _image(name: str, value: Any, size: tuple, channels: Sequence[int], like: str) -> np.ndarray:
    """`value` as an array of shape (H, W, c) with c in `channels` (for 1: (H, W) too), or an
    InvalidArgumentError naming the argument and the shape expected."""
    array = np.asarray(value)
    if array.dtype.kind not in "fiub":
        raise InvalidArgumentError(f"{name}: dtype {array.dtype} is not a number type")
    ok = array.shape[:2] == size and (
        (array.ndim == 3 and array.shape[2] in channels) or (array.ndim == 2 and 1 in channels)
    )
    if not ok:
        choices = " or ".join(str(c) for c in channels)
        expected = f"({size[0]}, {size[1]}, {choices})"
        if 1 in channels:
            expected = f"({size[0]}, {size[1]}) or " + expected
        raise InvalidArgumentError(
            f"{name}: shape {_shape_text(array.shape)}, expected {expected}{like}"
        )
    return array


def _radiance(array: np.ndarray) -> np.ndarray:
    """A radiance or albedo array wider than float32 as float32, its finite values clamped to
    +-kMaxRadiance first as the library would clamp them: cast, 1e300 would become Inf, which the
    library replaces by 0 (a black pixel). NaN and +-Inf stay as they are (replaced by 0)."""
    if array.dtype.kind != "f" or array.dtype.itemsize <= 4:
        return array
    clamped = np.clip(array, -_MAX_RADIANCE, _MAX_RADIANCE).astype(np.float32)
    infinite = np.isinf(array)  # np.clip made them +-kMaxRadiance
    if infinite.any():
        clamped[infinite] = array[infinite]
    return clamped


def _one_channel(name: str, value: Any, size: tuple, like: str) -> Optional[np.ndarray]:
    """An optional 1-channel input as float (the C API reads float or half)."""
    if value is None:
        return None
    image = _image(name, value, size, (1,), like)
    return image if image.dtype.kind == "f" else image.astype(np.float32)


def _unprojection(world_to_screen: np.ndarray, width: int, height: int):
    """The camera centre c and, per pixel centre, the world-space step v per unit of view depth:
    the point at view depth w on pixel (x, y)'s ray is c + w v. Rows 0, 1 and 3 of s = M p give
    s.x = (x + 0.5) w, s.y = (y + 0.5) w, s.w = w: linear in p, one 3x3 matrix for all pixels."""
    m = world_to_screen.astype(np.float64)
    a = m[[0, 1, 3], :3]
    if not np.linalg.cond(a) < 1e12:
        raise InvalidArgumentError(
            "matrices: world_to_screen's rows 0, 1 and 3 are singular: cannot unproject depth"
        )
    inverse = np.linalg.inv(a)
    centre = -inverse @ m[[0, 1, 3], 3]
    xs = np.arange(width, dtype=np.float64) + 0.5
    ys = np.arange(height, dtype=np.float64) + 0.5
    pixel = np.stack(np.broadcast_arrays(xs[None, :], ys[:, None], np.ones((1, 1))), axis=-1)
    step = pixel @ inverse.T  # (H, W, 3)
    return centre, step


def _position_from_depth(depth, world_to_screen, depth_kind: str) -> np.ndarray:
    height, width = depth.shape[:2]
    centre, step = _unprojection(world_to_screen, width, height)
    d = np.asarray(depth, dtype=np.float64).reshape(height, width, 1)
    if depth_kind == "ray-distance":  # the distance along the ray: w = d / |v|
        d = d / np.linalg.norm(step, axis=-1, keepdims=True)
    return (centre + d * step).astype(np.float32)


def _depth_from_position(position, world_to_screen, depth_kind: str) -> np.ndarray:
    p = np.asarray(position, dtype=np.float64)[..., :3]
    m = world_to_screen.astype(np.float64)
    if depth_kind == "ray-distance":
        centre, _ = _unprojection(world_to_screen, p.shape[1], p.shape[0])
        return np.linalg.norm(p - centre, axis=-1).astype(np.float32)
    return (p @ m[3, :3] + m[3, 3]).astype(np.float32)


def _object_count_of(ids: np.ndarray) -> int:
    """The largest ID + 1 (float IDs rounded, as the library rounds them)."""
    if ids.size == 0:
        return 0
    top = np.nanmax(ids) if ids.dtype.kind == "f" else ids.max()
    count = int(np.rint(top)) + 1 if np.isfinite(top) else 0
    if count > _INT32_MAX:
        raise Error(
            f"ids: ID {count - 1} is out of range: the library takes IDs up to "
            f"{_INT32_MAX - 1} (object_count up to {_INT32_MAX})",
            ErrorCode.INVALID_INPUT,
        )
    return count


def _checked_object_count(value: Any) -> Optional[int]:
    """object_count as an int in the library's range 0..2^31-1, or an InvalidArgumentError."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise InvalidArgumentError(
            f"object_count: expected an int in 0..{_INT32_MAX}, got {type(value).__name__} "
            f"{value!r}"
        )
    if not 0 <= int(value) <= _INT32_MAX:
        raise InvalidArgumentError(f"object_count: {value} is out of range 0..{_INT32_MAX}")
    return int(value)


def _setting_name(name: str) -> str:
    return name.replace("_", "-")


class Denoiser:
    """One sequence's denoiser: a method on a device, its settings, and the history it keeps
    across denoise() calls (one frame per call). Not for two threads at once (one per thread or
    stream); the filtering itself runs without the GIL.

    method: "jbf", "atrous", "temporal", "svgf", "detail" or "learned"; None: the library's
    default (detail). weights="FILE": the learned method's own weights (training/train.py).
    device: "default" (a CUDA GPU when there is one, else the CPU), "cpu" or "cuda".
    settings: the command line's options, underscores for hyphens (sigma_color=0.6,
    svgf_iterations=3, outlier=False, spatial_filter="jbf", depth_kind="ray-distance",
    motion_scale=(1, -1)); `rtdenoise denoise --help` lists them with their ranges.
    A bad method, device, setting name or value raises InvalidArgumentError; a device this
    build or machine lacks raises Error with code UNSUPPORTED_DEVICE. A Denoiser cannot be
    copied or pickled (a copy would share its history): make one per sequence.
    """

    def __init__(self, method: Optional[str] = None, device: str = "default", **settings: Any):
        if not isinstance(device, str) or device.lower() not in _DEVICES:
            raise InvalidArgumentError(
                f"device: {device!r} is not one of 'default', 'cpu', 'cuda'"
            )
        if method is not None and not isinstance(method, str):
            raise InvalidArgumentError(f"method: expected a name, got {type(method).__name__}")
        self._core = _native.Denoiser(method and method.lower(), _DEVICES[device.lower()])
        self._method = self._core.get("method")  # the library's name, the default's too
        self._depth_kind = "view-z"
        self._lock = threading.Lock()  # held by the one call under way (_exclusive)
        self._owner: Optional[int] = None  # the thread holding it
        self._closing = False
        # The library keeps the last matrices given, and their count then bounds the IDs of a
        # frame without motion: see denoise().
        self._matrices_given = False
        for name, value in settings.items():
            self.set(name, value)

    @property
    def method(self) -> str:
        return self._method

    @property
    def device_name(self) -> str:
        """Where it runs: "cpu (2 threads, avx512)", "cuda (NVIDIA H100 80GB HBM3)"."""
        return self._open().device_name

    def set(self, name: str, value: Any) -> None:
        """Sets one setting: name with underscores or hyphens ("sigma_color", "sigma-color");
        a bool, int, float or str value (motion_scale: an (x, y) pair). Changing a setting
        after the first frame takes effect at the next one, over the history kept, unless it changes
        the method's passes (method, an iteration count, a radius, outlier, albedo)."""
        key = _setting_name(name)
        with self._exclusive():
            if key == "motion-scale":
                try:
                    x, y = value
                except (TypeError, ValueError):
                    raise InvalidArgumentError(
                        f"motion_scale: expected an (x, y) pair, got {value!r}"
                    ) from None
                self._set_one("motion-scale-x", x)
                self._set_one("motion-scale-y", y)
                return
            self._set_one(key, value)
            if key == "depth-kind":
                self._depth_kind = str(value)
            elif key == "method":
                self._method = self._core.get("method")

    def _set_one(self, key: str, value: Any) -> None:
        if isinstance(value, (bool, np.bool_)):
            self._core.set_bool(key, bool(value))
        elif isinstance(value, numbers.Integral):
            if not -(2**31) <= int(value) < 2**31:
                raise InvalidArgumentError(f"{key}: {value} is out of range")
            self._core.set_int(key, int(value))
        elif isinstance(value, numbers.Real):
            self._core.set_float(key, float(value))
        elif isinstance(value, (str, os.PathLike)):
            self._core.set_string(key, os.fspath(value))
        else:
            raise InvalidArgumentError(
                f"{key}: expected a bool, int, float or str, got {type(value).__name__}"
            )

    def get(self, name: str) -> Any:
        """A setting's value (bool, int, float or str), by the names set() takes."""
        key = _setting_name(name)
        with self._exclusive():
            if key == "motion-scale":
                return (self._core.get("motion-scale-x"), self._core.get("motion-scale-y"))
            return self._core.get(key)

    def reset(self) -> None:
        """Forgets the history (a camera cut): the next frame is denoised as a first one."""
        with self._exclusive():
            self._core.reset()

    def denoise(
        self,
        color: Any,
        normal: Any,
        position: Any = None,
        depth: Any = None,
        ids: Any = None,
        albedo: Any = None,
        motion: Any = None,
        matrices: Any = None,
        out: Optional[np.ndarray] = None,
        *,
        confidence: Any = None,
        specular: Any = None,
        roughness: Any = None,
        hit_distance: Any = None,
        depth_kind: Optional[str] = None,
        object_count: Optional[int] = None,
    ) -> np.ndarray:
        """Denoises the next frame of the sequence; returns (H, W, 3) float32, or `out`.

        color (H, W, 3 or 4; a 4th value ignored): noisy linear radiance. normal: world-space
        unit normal, (0, 0, 0) on background. position: world-space position; depth (H, W): view
        depth (depth_kind "view-z", the default) or ray distance ("ray-distance"). Either one
        with `matrices` gives the other. ids (H, W) int: object IDs, -1 on background (None:
        one object, background where the normal is 0). albedo: optional, as color.
        motion (H, W, 2 or 3): pixels, previous = current + motion; or matrices (a Matrices,
        a mapping, a frame's): object_to_world (K, 4, 4), world_to_camera, world_to_screen.
        object_count: without matrices, IDs are -1..object_count-1 (None: the largest ID + 1;
        at most 2^31-1); no matrices are built for it.
        confidence (H, W): optional history confidence in [0, 1] (NRD's IN_DIFF_CONFIDENCE: 0
        where the lighting changed, drop the history; clamped, NaN as 1).
        specular (H, W, 3 or 4), roughness (H, W), hit_distance (H, W): the optional split
        signal, read by method "detail" only: the part of color that left the first surface
        through its glossy lobe (albedo is then the diffuse albedo), its roughness in [0, 1]
        (sqrt of GGX alpha; needed with specular), and the world distance its specular ray
        travelled to a hit (0: unknown; optional).
        out: an (H, W, 3 or 4) float32 or float16 array to write (4: alpha 1; give out[..., :3]
        to keep its alpha).

        float32 and float16 arrays (int32 ids) are read where they lie when each pixel's values
        are contiguous (a slice such as rgba[..., :3] is); others are converted to float32,
        float64 color, albedo and specular clamped to +-1e16 first (as the library clamps
        float32 ones; cast, a value beyond float32's range would be Inf, replaced by 0).
        """
        color = np.asarray(color)
        if color.ndim != 3:
            raise InvalidArgumentError(
                f"color: shape {_shape_text(color.shape)}, expected (H, W, 3 or 4)"
            )
        color = _radiance(_image("color", color, color.shape[:2], (3, 4), ""))
        size = color.shape[:2]
        like = " like color"
        normal = _image("normal", normal, size, (3, 4), like)
        kind = self._depth_kind if depth_kind is None else depth_kind
        if kind not in ("view-z", "ray-distance"):
            raise InvalidArgumentError(
                f"depth_kind: {kind!r} is not one of 'view-z', 'ray-distance'"
            )
        if matrices is not None:
            matrices = Matrices.of(matrices)
        if motion is not None:
            motion = _image("motion", motion, size, (2, 3), like)
        elif matrices is None and self._method in _TEMPORAL_METHODS:
            raise InvalidArgumentError(
                f"{self._method} needs motion or matrices to reproject its history: give one"
            )
        if position is not None:
            position = _image("position", position, size, (3, 4), like)
        if depth is not None:
            depth = _image("depth", depth, size, (1,), like)
        if position is None or depth is None:
            if matrices is None or (position is None and depth is None):
                missing = [n for n, v in (("position", position), ("depth", depth)) if v is None]
                have = "matrices" if matrices is not None else "no matrices"
                raise InvalidArgumentError(
                    f"{' and '.join(missing)} missing: give position and depth, or one of them "
                    f"with matrices to compute the other ({have} given)"
                )
            if depth is None:
                depth = _depth_from_position(position, matrices.world_to_screen, kind)
            else:
                position = _position_from_depth(depth, matrices.world_to_screen, kind)
        if ids is None:
            ids = np.where(np.any(normal[..., :3] != 0, axis=-1), 0, -1).astype(np.int32)
        else:
            ids = _image("ids", ids, size, (1,), like)
            if ids.dtype != np.int32 and ids.dtype.kind in "iub":
                if ids.size and (ids.min() < -1 or ids.max() >= 2**31):
                    raise InvalidArgumentError("ids: values outside -1..2^31-1")
                ids = ids.astype(np.int32)
            elif ids.dtype.kind == "f" and ids.dtype != np.float32:  # the C API rounds float32
                ids = ids.astype(np.float32)
        if albedo is not None:
            albedo = _radiance(_image("albedo", albedo, size, (3, 4), like))
        confidence = _one_channel("confidence", confidence, size, like)
        if specular is not None:
            specular = _radiance(_image("specular", specular, size, (3, 4), like))
        roughness = _one_channel("roughness", roughness, size, like)
        hit_distance = _one_channel("hit_distance", hit_distance, size, like)
        object_count = _checked_object_count(object_count)
        if object_count is None:
            object_count = _object_count_of(ids)
        result, written = self._output(out, size)
        inputs = {
            "color": (color, color.shape[2]),
            "normal": (normal, normal.shape[2]),
            "position": (position, position.shape[2]),
            "depth": (depth, 1),
            "ids": (ids, 1),
            "albedo": (albedo, 0 if albedo is None else albedo.shape[2]),
            "motion": (motion, 0 if motion is None else motion.shape[2]),
            "confidence": (confidence, 1),
            "specular": (specular, 0 if specular is None else specular.shape[2]),
            "roughness": (roughness, 1),
            "hit_distance": (hit_distance, 1),
        }
        with self._exclusive():
            if kind != self._depth_kind:
                self._core.set_string("depth-kind", kind)
                self._depth_kind = kind
            try:
                for name, (array, channels) in inputs.items():
                    self._bind(name, array, channels)
                self._bind_output(written)
                if matrices is not None:
                    self._core.set_matrices(
                        matrices.object_to_world,
                        matrices.world_to_camera,
                        matrices.world_to_screen,
                    )
                    self._matrices_given = True
                else:  # motion, or a single-frame method: the object count bounds the IDs
                    if self._matrices_given:
                        # An earlier frame's matrices (and their count) would still apply.
                        self._core.unset_matrices()
                        self._matrices_given = False
                    self._core.set_object_count(object_count)
                self._core.execute()
                broken = self._core.frame_warning()
            finally:
                # Holds no reference to the caller's arrays between frames.
                for name in list(inputs) + ["output"]:
                    self._core.set_image(name, None, 0, 0, 0)
        if written is not result:
            np.copyto(result, written, casting="unsafe")
        if broken:  # a broken pass: the frame came back as noisy as it went in
            warnings.warn(f"rtdenoise: {broken}", RuntimeWarning, stacklevel=2)
        return result

    def denoise_frame(self, frame: Frame, out: Optional[np.ndarray] = None) -> np.ndarray:
        """Denoises a Frame read by open_sequence (its depth kind and object count too)."""
        return self.denoise(**frame.inputs(), out=out)

    def close(self) -> None:
        """Frees the denoiser and its device memory now (else when it is collected). A call
        under way in another thread finishes its frame first; calls after it raise Error."""
        if self._owner == threading.get_ident():
            raise Error(
                "close() inside a call of this denoiser: close it after the call returns",
                ErrorCode.INVALID_OPERATION,
            )
        self._closing = True  # calls that start while close() waits are refused, not queued
        with self._lock:
            self._core = None

    def _not_copyable(self, *args) -> NoReturn:
        raise Error(
            "a Denoiser cannot be copied or pickled: the copy would share its history (one "
            "sequence's). Make another with rtdenoise.Denoiser(method, device, **settings)",
            ErrorCode.INVALID_OPERATION,
        )

    __copy__ = __deepcopy__ = __reduce_ex__ = __reduce__ = _not_copyable

    def __enter__(self) -> "Denoiser":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        core = self._core  # read once: close() in another thread may clear it
        state = core.device_name if core is not None else "closed"
        return f"<rtdenoise.Denoiser {self._method} on {state}>"

    # -- helpers --

    def _open(self):
        core = self._core
        if core is None or self._closing:
            raise Error("the denoiser is closed", ErrorCode.INVALID_OPERATION)
        return core

    @contextlib.contextmanager
    def _exclusive(self):
        """Holds the denoiser for one call: a second thread gets an error, not a torn frame,
        and close() waits for the call."""
        self._open()
        if not self._lock.acquire(blocking=False):
            raise Error(
                "the denoiser is in use by another thread: use one Denoiser per thread",
                ErrorCode.INVALID_OPERATION,
            )
        self._owner = threading.get_ident()
        try:
            self._open()  # again, under the lock: close() may have run meanwhile
            yield
        finally:
            self._owner = None
            self._lock.release()

    def _bind(self, name: str, array: Optional[np.ndarray], channels: int) -> None:
        if array is None:
            self._core.set_image(name, None, 0, 0, 0)
            return
        binding = _Binding(array, channels)
        self._core.set_image(
            name, binding.array, binding.format, binding.pixel_stride, binding.row_stride
        )

    def _bind_output(self, written: np.ndarray) -> None:
        layout = _in_place_layout(written, written.shape[2])
        assert layout is not None  # _output() made it so
        self._core.set_image("output", written, *layout)

    @staticmethod
    def _output(out: Optional[np.ndarray], size: tuple):
        """(the array returned, the array the C API writes): the same unless `out` is in a
        layout it cannot write, which then gets a float32 copy of the result."""
        if out is None:
            result = np.empty(size + (3,), np.float32)
            return result, result
        if not isinstance(out, np.ndarray):
            raise InvalidArgumentError(f"out: expected a numpy array, got {type(out).__name__}")
        if out.ndim != 3 or out.shape[:2] != size or out.shape[2] not in (3, 4):
            raise InvalidArgumentError(
                f"out: shape {_shape_text(out.shape)}, expected ({size[0]}, {size[1]}, 3 or 4)"
                " like color"
            )
        if out.dtype.kind != "f":
            raise InvalidArgumentError(f"out: dtype {out.dtype}, expected float32 or float16")
        if not out.flags.writeable:
            raise InvalidArgumentError("out: the array is read-only")
        if _in_place_layout(out, out.shape[2]) is not None:
            return out, out
        return out, np.empty(out.shape, np.float32)


# ---- metrics ----


@dataclasses.dataclass
class FrameMetrics:
    """A frame's quality against its reference, as `rtdenoise compare` prints it: mse, relmse
    and energy_ratio (result_mean / reference_mean) on the linear RGB; psnr (dB, inf when
    identical), ssim and temporal_error (None for the first frame) on the tone-mapped images."""

    mse: float
    relmse: float
    psnr: float
    ssim: float
    temporal_error: Optional[float] = None
    result_mean: float = 0.0
    reference_mean: float = 0.0

    @property
    def energy_ratio(self) -> float:
        """The result's light over the reference's (1: kept; NaN for a black reference)."""
        return self.result_mean / self.reference_mean if self.reference_mean else float("nan")


@dataclasses.dataclass
class Comparison:
    """compare()'s result: one FrameMetrics per frame and their means (temporal_error over the
    frames that have one)."""

    frames: list
    mean: FrameMetrics

    def table(self) -> str:
        """The table `rtdenoise compare` prints."""

        def sci(v: Optional[float]) -> str:
            return "-" if v is None else f"{v:.4e}" if np.isfinite(v) else str(v)

        def row(label: str, m: FrameMetrics) -> str:
            return (
                f"{label:>5}  {sci(m.mse):>11}  {sci(m.relmse):>11}  {m.psnr:>9.2f}  "
                f"{m.ssim:>7.4f}  {sci(m.temporal_error):>11}  {m.energy_ratio:>7.4f}\n"
            )

        header = (
            f"{'frame':>5}  {'MSE':>11}  {'relMSE':>11}  {'PSNR (dB)':>9}  {'SSIM':>7}  "
            f"{'temporal':>11}  {'energy':>7}\n"
        )
        rows = [row(str(i), m) for i, m in enumerate(self.frames)]
        return header + "".join(rows) + row("mean", self.mean)


def _rgb(name: str, image: Any) -> np.ndarray:
    array = np.asarray(image)
    if array.ndim != 3 or array.shape[2] not in (3, 4):
        raise InvalidArgumentError(
            f"{name}: shape {_shape_text(array.shape)}, expected (H, W, 3 or 4)"
        )
    return np.ascontiguousarray(array[..., :3], dtype=np.float32)


def metrics(result: Any, reference: Any, exposure: float = 1.0) -> FrameMetrics:
    """One frame's metrics (no temporal error): result and reference (H, W, 3 or 4) linear RGB."""
    _check_exposure(exposure)
    values = _native.compare_frame(
        _rgb("result", result), _rgb("reference", reference), float(exposure)
    )
    return FrameMetrics(**values)


def _check_exposure(exposure: float) -> None:
    if not (isinstance(exposure, numbers.Real) and np.isfinite(exposure) and exposure > 0):
        raise InvalidArgumentError(f"exposure must be a finite number > 0, got {exposure!r}")


_NUMBERED = re.compile(r"^(?:(?P<stem>result|reference)_)?(?P<index>[0-9]+)\.exr$")


def _exr_files(folder: str, role: str) -> list:
    """A folder's result_<i>.exr (or reference_<i>.exr, or numbered 0001.exr) files in order."""
    if not os.path.isdir(folder):
        raise MissingFileError(f"{folder}: no such folder ({role})")
    by_kind: dict = {}
    for name in os.listdir(folder):
        match = _NUMBERED.match(name)
        if match:
            by_kind.setdefault(match["stem"], []).append((int(match["index"]), name))
    for kind in ("result", "reference", None):
        if kind in by_kind:
            files = sorted(by_kind[kind])
            if kind is not None and [i for i, _ in files] != list(range(len(files))):
                raise Error(
                    f"{folder}: {kind}_<i>.exr not numbered 0..{len(files) - 1}",
                    ErrorCode.INVALID_INPUT,
                )
            return [os.path.join(folder, name) for _, name in files]
    raise MissingFileError(
        f"{folder}: no result_<i>.exr, reference_<i>.exr or numbered EXRs ({role})"
    )


def _images(value: Any, role: str):
    """(count, an iterator of arrays) for a sequence of arrays or a folder of EXRs."""
    if isinstance(value, (str, os.PathLike)):
        files = _exr_files(os.fspath(value), role)
        return len(files), (read_exr(f) for f in files)
    if isinstance(value, np.ndarray) and value.ndim == 4:
        return len(value), iter(value)
    items = list(value)
    return len(items), iter(items)


def compare(results: Any, references: Any, exposure: float = 1.0) -> Comparison:
    """The metrics of `rtdenoise compare`, per frame and their means: `results` and
    `references` are equally long sequences of (H, W, 3 or 4) linear RGB arrays (or an
    (N, H, W, C) array), or folders (result_<i>.exr; reference_<i>.exr or numbered EXRs).
    exposure multiplies the images before the tone map of psnr, ssim and temporal_error."""
    _check_exposure(exposure)
    result_count, result_images = _images(results, "results")
    reference_count, reference_images = _images(references, "references")
    if result_count != reference_count:
        raise InvalidArgumentError(
            f"{result_count} results but {reference_count} references: give as many of each"
        )
    if result_count == 0:
        raise InvalidArgumentError("no frames to compare")
    comparer = _native.SequenceComparer(float(exposure))
    frames = []
    for i, (result, reference) in enumerate(zip(result_images, reference_images)):
        try:
            values = comparer.add_frame(_rgb("result", result), _rgb("reference", reference))
        except Error as error:
            raise type(error)(f"frame {i}: {error.message}", error.code) from None
        frames.append(FrameMetrics(**values))
    mean = _native.mean_of([dataclasses.asdict(f) for f in frames])
    return Comparison(frames, FrameMetrics(**mean))
