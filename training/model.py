"""Stage 3: the network and the differentiable filter of the `learned` method
(docs/learned_spec.md).

    f = features(raw)                      14 features (features.py)
    x = (f - mean) / std * keep            input normalisation (buffers; export.py folds it
                                           into W1/b1; keep zeroes a dropped feature)
    h1 = relu(W1 x + b1)  (16)
    h2 = relu(W2 h1 + b2) (16)
    w  = softmax(W3 h2 + b3) (6)           weights of the candidates L0..L5
    out = albedo * clamp(sum_k w_k L_k.rgb, min(E, L5), max(E, L5))   foreground pixels
                                           (E: L0 drawn towards L5 by its noise, range_end)
    out = albedo * L0.rgb                  background pixels (foreground = 0)
"""

import torch
from torch import nn

from features import ALBEDO, CANDIDATES, FEATURES, FOREGROUND, candidates, features, lum

HIDDEN = 16

# How many standard errors of L0's mean the range's L0 end is drawn towards L5 (kernels/learned.h).
L0_NOISE_MARGIN = 2.0


def range_end(l0, l5, v0):
    """The unfiltered end of the mix's range (kernels/learned.h learnedRangeEnd): L0 (..., 3)
    drawn towards L5 by L0_NOISE_MARGIN standard errors of its mean (v0: its luminance
    variance, (...)). Any float dtype."""
    gap = (lum(*l0.unbind(-1)) - lum(*l5.unbind(-1))).abs()
    noise = L0_NOISE_MARGIN * torch.sqrt(torch.clamp(v0, min=0.0))
    beyond_noise = torch.clamp(gap - noise, min=0.0)
    return l5 + (l0 - l5) * (beyond_noise / torch.clamp(gap, min=1e-20)).unsqueeze(-1)


def clamp_to_range(mixed, cand, v0):
    """mixed (..., 3) kept per channel between L5 and range_end (cand: (..., 6, 3))."""
    end = range_end(cand[..., 0, :], cand[..., -1, :], v0)
    low = torch.minimum(end, cand[..., -1, :])
    high = torch.maximum(end, cand[..., -1, :])
    return torch.minimum(torch.maximum(mixed, low), high)


class LearnedMix(nn.Module):
    def __init__(self, drop_feature=None):
        super().__init__()
        self.fc1 = nn.Linear(FEATURES, HIDDEN)
        self.fc2 = nn.Linear(HIDDEN, HIDDEN)
        self.fc3 = nn.Linear(HIDDEN, CANDIDATES)
        self.register_buffer("mean", torch.zeros(FEATURES))
        self.register_buffer("std", torch.ones(FEATURES))
        keep = torch.ones(FEATURES)
        dropped = [] if drop_feature is None else (
            [drop_feature] if isinstance(drop_feature, int) else list(drop_feature))
        for k in dropped:  # one feature or several (an ablation's group)
            if not 0 <= k < FEATURES:
                raise ValueError(f"drop_feature {k}: features are 0..{FEATURES - 1}")
            keep[k] = 0.0
        self.register_buffer("keep", keep)

    def set_normalisation(self, mean, std):
        """Per-feature mean and std (of the train set's foreground samples); a feature that does
        not vary keeps std 1."""
        std = torch.as_tensor(std, dtype=torch.float32)
        std = torch.where(std > 1e-6, std, torch.ones_like(std))
        self.mean.copy_(torch.as_tensor(mean, dtype=torch.float32))
        self.std.copy_(std)

    def mix_weights(self, feats):
        """(..., 14) features -> (..., 6) softmax weights."""
        x = (feats - self.mean) / self.std * self.keep
        h = torch.relu(self.fc1(x))
        h = torch.relu(self.fc2(h))
        return torch.softmax(self.fc3(h), dim=-1)

    def forward(self, raw, return_weights=False):
        """(..., 29) raw channels -> (..., 3) filtered radiance."""
        w = self.mix_weights(features(raw))
        cand = candidates(raw)  # (..., 6, 3)
        mixed = (w.unsqueeze(-1) * cand).sum(dim=-2)
        # Kept between L5 and L0 drawn towards it by its noise, per channel (kernels/learned.h).
        mixed = clamp_to_range(mixed, cand, raw[..., 3])
        albedo = raw[..., ALBEDO]
        foreground = raw[..., FOREGROUND:FOREGROUND + 1] > 0.5
        out = albedo * torch.where(foreground, mixed, cand[..., 0, :])
        return (out, w) if return_weights else out

    def folded(self):
        """The weights with the normalisation (and a dropped feature) folded into W1/b1, as
        float32 numpy arrays: W1' = W1 diag(keep/std), b1' = b1 - W1' mean."""
        with torch.no_grad():
            scale = (self.keep / self.std).double()
            w1 = self.fc1.weight.double() * scale[None, :]
            b1 = self.fc1.bias.double() - w1 @ self.mean.double()
            return {
                "w1": w1.float().cpu().numpy(), "b1": b1.float().cpu().numpy(),
                "w2": self.fc2.weight.detach().float().cpu().numpy(),
                "b2": self.fc2.bias.detach().float().cpu().numpy(),
                "w3": self.fc3.weight.detach().float().cpu().numpy(),
                "b3": self.fc3.bias.detach().float().cpu().numpy(),
            }


class FoldedMix(nn.Module):
    """The network from a weights file's arrays (already folded): what the C++ library runs."""

    def __init__(self, weights):
        super().__init__()
        for name in ("w1", "b1", "w2", "b2", "w3", "b3"):
            self.register_buffer(name, torch.as_tensor(weights[name], dtype=torch.float32))

    def mix_weights(self, feats):
        h = torch.relu(feats @ self.w1.T + self.b1)
        h = torch.relu(h @ self.w2.T + self.b2)
        return torch.softmax(h @ self.w3.T + self.b3, dim=-1)

    forward = LearnedMix.forward
