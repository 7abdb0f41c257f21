"""Stage 1: the 14 per-pixel features of the `learned` method from the 29 dumped channels.

The arithmetic is docs/learned_spec.md's, in float32, in the same order as written there, so that
the C++ library (src/) and PyTorch compute the same numbers (to float32 rounding: the C++ build
may contract a*b+c into fused multiply-adds).

    CHANNELS             the 29 channel names of learned-inputs_<n>.exr, in the order used here
    features(raw)        (..., 29) float32 tensor -> (..., 14) float32 tensor
    candidates(raw)      (..., 29) -> (..., 6, 3): the demodulated rgb of L0..L5
"""

import torch

CANDIDATES = 6
FEATURES = 14
# L0.R L0.G L0.B L0.V ... L5.R L5.G L5.B L5.V, history, albedo.R albedo.G albedo.B, foreground.
CHANNELS = [f"L{k}.{c}" for k in range(CANDIDATES) for c in "RGBV"] + [
    "history", "albedo.R", "albedo.G", "albedo.B", "foreground",
]
HISTORY = 24
ALBEDO = slice(25, 28)
FOREGROUND = 28
# The rgb channels (which a colour permutation permutes) and the variances (which an exposure
# scale s multiplies by s^2).
RGB_TRIPLES = [(4 * k, 4 * k + 1, 4 * k + 2) for k in range(CANDIDATES)] + [(25, 26, 27)]
RADIANCE_RGB = [4 * k + c for k in range(CANDIDATES) for c in range(3)]
VARIANCES = [4 * k + 3 for k in range(CANDIDATES)]

FEATURE_NAMES = (
    ["log_rel_sigma0", "history_fraction", "inv_history"]
    + [f"softsign_dl{j + 1}{j}" for j in range(5)]
    + [f"log_rel_sigma{k}" for k in range(CANDIDATES)]
)
assert len(CHANNELS) == 29 and len(FEATURE_NAMES) == FEATURES


def _f32(value):
    return torch.tensor(value, dtype=torch.float32)


def lum(r, g, b):
    """0.2126*R + 0.7152*G + 0.0722*B, float32, summed left to right."""
    return _f32(0.2126) * r + _f32(0.7152) * g + _f32(0.0722) * b


def softsign(x):
    return x / (1.0 + torch.abs(x))


def candidates(raw):
    """(..., 29) -> (..., 6, 3): the rgb of L0..L5."""
    shape = raw.shape[:-1]
    return raw[..., : 4 * CANDIDATES].reshape(*shape, CANDIDATES, 4)[..., :3]


def features(raw):
    """The 14 features of docs/learned_spec.md, (..., 29) float32 -> (..., 14) float32."""
    if raw.shape[-1] != len(CHANNELS):
        raise ValueError(f"features: {raw.shape[-1]} channels, expected {len(CHANNELS)}")
    raw = raw.to(torch.float32)
    one = _f32(1.0)
    zero = _f32(0.0)
    l = [lum(raw[..., 4 * k], raw[..., 4 * k + 1], raw[..., 4 * k + 2]) for k in range(CANDIDATES)]
    v = [raw[..., 4 * k + 3] for k in range(CANDIDATES)]
    history = raw[..., HISTORY]
    ref = _f32(0.5) * (torch.abs(l[0]) + torch.abs(l[5])) + _f32(1e-4)
    s0 = torch.sqrt(torch.maximum(v[0], zero))
    noise = s0 + _f32(0.1) * ref
    out = [
        torch.log(one + s0 / ref),
        torch.minimum(history, _f32(32.0)) / _f32(32.0),
        one / torch.maximum(history, one),
    ]
    out += [softsign((l[j + 1] - l[j]) / noise) for j in range(5)]
    out += [torch.log(one + torch.sqrt(torch.maximum(v[k], zero)) / ref) for k in range(CANDIDATES)]
    return torch.stack(out, dim=-1)


def features_float64(raw):
    """The same formulas in float64: how far float32 rounding moves them (infer.known_answer)."""
    raw = raw.to(torch.float64)
    l = [0.2126 * raw[..., 4 * k] + 0.7152 * raw[..., 4 * k + 1] + 0.0722 * raw[..., 4 * k + 2]
         for k in range(CANDIDATES)]
    v = [raw[..., 4 * k + 3].clamp_min(0.0) for k in range(CANDIDATES)]
    history = raw[..., HISTORY]
    ref = 0.5 * (l[0].abs() + l[5].abs()) + 1e-4
    noise = v[0].sqrt() + 0.1 * ref
    out = [torch.log(1.0 + v[0].sqrt() / ref), history.clamp(max=32.0) / 32.0,
           1.0 / history.clamp(min=1.0)]
    out += [softsign((l[j + 1] - l[j]) / noise) for j in range(5)]
    out += [torch.log(1.0 + v[k].sqrt() / ref) for k in range(CANDIDATES)]
    return torch.stack(out, dim=-1)
