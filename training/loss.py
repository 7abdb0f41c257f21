"""Stage 4: the HDR training loss.

    SMAPE     mean |x - r| / (|x| + |r| + 0.01), linear RGB (bounded: robust to fireflies)
    relMSE    mean over samples and channels of (x - r)^2 / (r^2 + 0.01), linear RGB (the
              project's relMSE metric, src/metrics)
    L1        mean |T(x) - T(r)| on tone-mapped values
    temporal  mean |e_t - e_{t-1}|, e = T(x) - T(r), on the same pixel in consecutive frames:
              |(T(x_t) - T(x_{t-1})) - (T(r_t) - T(r_{t-1}))|, the form of the project's temporal
              error metric (which uses its display transform, ACES + sRGB; tonemap="display")

T is x/(1+x) (tonemap="reinhard", the default) or the project's display transform
(tonemap="display": Narkowicz's ACES fit, then the sRGB curve; src/io/tone_map.cpp).
loss = w_relmse * relMSE + w_smape * SMAPE + w_l1 * L1 + w_temporal * temporal.
"""

from dataclasses import dataclass

import torch

REL_MSE_EPSILON = 0.01


def reinhard(x):
    x = torch.clamp(x, min=0.0)
    return x / (1.0 + x)


def display(x):
    """src/io/tone_map.cpp's toneMap at exposure 1 (differentiable almost everywhere)."""
    x = torch.clamp(x, min=0.0, max=1.0e6)
    y = torch.clamp(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    linear = 12.92 * y
    curve = 1.055 * torch.pow(torch.clamp(y, min=0.0031308), 1.0 / 2.4) - 0.055
    return torch.where(y <= 0.0031308, linear, curve)


def log1p_tonemap(x):
    """log(1 + x): unbounded, so a pixel 100x too bright costs about log(100), not a clipped 1."""
    return torch.log1p(torch.clamp(x, min=0.0))


TONEMAPS = {"reinhard": reinhard, "display": display, "log": log1p_tonemap}


def rel_mse(x, r, clip=0.0):
    """clip > 0: each value's term at most clip (a few pixels then cannot outweigh the rest)."""
    e = (x - r) ** 2 / (r * r + REL_MSE_EPSILON)
    return (torch.clamp(e, max=clip) if clip > 0 else e).mean()


def smape(x, r):
    """|x - r| / (|x| + |r| + 0.01), linear RGB: bounded by 1, so a firefly left in a dark
    pixel costs what it should without one pixel outweighing thousands (relMSE's flaw)."""
    return (torch.abs(x - r) / (torch.abs(x) + torch.abs(r) + REL_MSE_EPSILON)).mean()


@dataclass
class LossWeights:
    relmse: float = 1.0
    smape: float = 0.0
    l1: float = 1.0
    temporal: float = 1.0
    tonemap: str = "reinhard"
    relmse_clip: float = 0.0


def hdr_loss(x, r, x_prev=None, r_prev=None, weights=LossWeights()):
    """Returns (loss, parts): parts holds each term's value (detached floats)."""
    t = TONEMAPS[weights.tonemap]
    tx, tr = t(x), t(r)
    parts = {"relmse": rel_mse(x, r, weights.relmse_clip), "smape": smape(x, r), "l1": torch.abs(tx - tr).mean()}
    loss = (weights.relmse * parts["relmse"] + weights.smape * parts["smape"] +
            weights.l1 * parts["l1"])
    if weights.temporal > 0 and x_prev is not None:
        e = tx - tr
        e_prev = t(x_prev) - t(r_prev)
        parts["temporal"] = torch.abs(e - e_prev).mean()
        loss = loss + weights.temporal * parts["temporal"]
    return loss, {k: float(v.detach()) for k, v in parts.items()}
