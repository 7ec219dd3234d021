"""Random Fourier positional encoding and farthest point sampling in torch."""

from __future__ import annotations

import math

import torch
from torch import nn


class FourierEncoding(nn.Module):
    """``[sin 2 pi x B, cos 2 pi x B]`` for ``x`` in ``[0, 1]^3`` with fixed ``B ~ N(0, scale^2)`` of shape (3, dim/2).

    ``B`` is drawn from a fixed seed so two models built with the same sizes encode identically.
    """

    def __init__(self, dim: int = 128, scale: float = 1.0, seed: int = 0):
        super().__init__()
        if dim % 2:
            raise ValueError(f"Fourier dim must be even, got {dim}")
        gen = torch.Generator().manual_seed(seed)
        self.register_buffer("B", torch.randn(3, dim // 2, generator=gen) * scale)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """``x`` (N, 3) float in [0, 1] -> (N, dim) float32 (computed outside autocast: bf16 would blur it)."""
        with torch.autocast(device_type=x.device.type, enabled=False):
            proj = 2 * math.pi * (x.float() @ self.B.float())
            return torch.cat([proj.sin(), proj.cos()], dim=-1)


def normalise_coords(xyz: torch.Tensor, lo: torch.Tensor, hi: torch.Tensor) -> torch.Tensor:
    """Map ``(N, 3)`` coordinates into ``[0, 1]`` using the scene bounds ``lo``/``hi`` (3,)."""
    return (xyz - lo) / (hi - lo).clamp(min=1e-6)


def farthest_point_sample(xyz: torch.Tensor, k: int) -> torch.Tensor:
    """Indices ``(min(k, N),) int64`` of ``k`` farthest points of ``xyz`` (N, 3), starting at row 0.

    Deterministic; one vectorised distance update per selected point (k iterations over all points).
    """
    n = xyz.shape[0]
    k = min(k, n)
    idx = torch.zeros(k, dtype=torch.int64, device=xyz.device)
    if k == 0:
        return idx
    pts = xyz.float()
    dist = torch.full((n,), float("inf"), device=xyz.device)
    cur = torch.zeros((), dtype=torch.int64, device=xyz.device)
    for i in range(k):
        idx[i] = cur
        d = ((pts - pts[cur]) ** 2).sum(1)
        dist = torch.minimum(dist, d)
        cur = torch.argmax(dist)
    return idx
