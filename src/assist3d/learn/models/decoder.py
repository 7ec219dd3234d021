"""The Mask3D transformer decoder: FPS queries, masked cross-attention over a feature pyramid.

Per scene: ``num_queries`` farthest-point-sampled voxels give the query positions (Fourier features of
the coordinates normalised to the scene bounds, then an MLP); query contents start at zero. Each layer
attends to one pyramid level (masked cross-attention: a query sees only the keys its current mask
covers, sigmoid >= 0.5 after pooling to that level; a query blocked everywhere sees everything), then
self-attention, then an FFN, all post-norm. ``num_passes`` passes over the levels; with
``shared=True`` every pass reuses the same per-level weights (Mask3D: 3 passes x 4 levels = 12 layers).
After the initial queries and after every layer the heads predict an objectness logit per query and
mask logits ``(N, Q)`` = full-resolution mask features dot a per-query mask embedding.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from .fourier import FourierEncoding, farthest_point_sample, normalise_coords


@dataclass
class LayerPrediction:
    """One decoder layer's output for one scene: ``objectness`` (Q,) logits, ``masks`` (N, Q) logits."""

    objectness: torch.Tensor
    masks: torch.Tensor


@dataclass
class SceneLevels:
    """Inputs of the decoder for one scene (local rows only).

    ``level_feats[l]`` (n_l, C) projected level features; ``level_pos[l]`` (n_l, C) positional encodings;
    ``level_index[l]`` (N,) level row of every full-resolution voxel; ``mask_feats`` (N, C);
    ``query_pos`` (Q, C).
    """

    level_feats: list[torch.Tensor]
    level_pos: list[torch.Tensor]
    level_index: list[torch.Tensor]
    mask_feats: torch.Tensor
    query_pos: torch.Tensor


class _Attention(nn.Module):
    def __init__(self, dim: int, heads: int, dropout: float):
        super().__init__()
        self.attn = nn.MultiheadAttention(dim, heads, dropout=dropout, batch_first=True)
        self.norm = nn.LayerNorm(dim)
        self.drop = nn.Dropout(dropout)
        self.heads = heads

    def forward(self, q: torch.Tensor, q_pos: torch.Tensor, k: torch.Tensor, k_pos: torch.Tensor,
                v: torch.Tensor, mask: torch.Tensor | None = None) -> torch.Tensor:
        out, _ = self.attn((q + q_pos)[None], (k + k_pos)[None], v[None], attn_mask=mask, need_weights=False)
        return self.norm(q + self.drop(out[0]))


class _FFN(nn.Module):
    def __init__(self, dim: int, hidden: int, dropout: float):
        super().__init__()
        self.net = nn.Sequential(nn.Linear(dim, hidden), nn.ReLU(), nn.Dropout(dropout), nn.Linear(hidden, dim))
        self.norm = nn.LayerNorm(dim)
        self.drop = nn.Dropout(dropout)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.norm(x + self.drop(self.net(x)))


class DecoderLayer(nn.Module):
    def __init__(self, dim: int, heads: int, ffn: int, dropout: float):
        super().__init__()
        self.cross = _Attention(dim, heads, dropout)
        self.self_attn = _Attention(dim, heads, dropout)
        self.ffn = _FFN(dim, ffn, dropout)

    def forward(self, q: torch.Tensor, q_pos: torch.Tensor, keys: torch.Tensor, k_pos: torch.Tensor,
                mask: torch.Tensor | None) -> torch.Tensor:
        q = self.cross(q, q_pos, keys, k_pos, keys, mask)
        q = self.self_attn(q, q_pos, q, q_pos, q)
        return self.ffn(q)


class MaskDecoder(nn.Module):
    def __init__(self, level_channels: list[int], mask_channels: int, hidden: int = 128, heads: int = 8,
                 ffn: int = 1024, dropout: float = 0.0, num_passes: int = 3, shared: bool = True,
                 sample_sizes: tuple[int, ...] = (200, 800, 3200, 12800)):
        super().__init__()
        self.num_levels = len(level_channels)
        if len(sample_sizes) != self.num_levels:
            raise ValueError(f"{len(sample_sizes)} key sample sizes for {self.num_levels} levels")
        self.num_passes = num_passes
        self.shared = shared
        self.sample_sizes = tuple(sample_sizes)
        self.heads = heads
        self.level_proj = nn.ModuleList([nn.Linear(c, hidden) for c in level_channels])
        self.mask_proj = nn.Linear(mask_channels, hidden)
        self.pos_enc = FourierEncoding(hidden)
        self.query_mlp = nn.Sequential(nn.Linear(hidden, hidden), nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU(),
                                       nn.Linear(hidden, hidden))
        n_layers = self.num_levels if shared else self.num_levels * num_passes
        self.layers = nn.ModuleList([DecoderLayer(hidden, heads, ffn, dropout) for _ in range(n_layers)])
        self.out_norm = nn.LayerNorm(hidden)
        self.objectness = nn.Linear(hidden, 1)
        self.mask_embed = nn.Sequential(nn.Linear(hidden, hidden), nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU(),
                                        nn.Linear(hidden, hidden))

    def queries(self, xyz: torch.Tensor, lo: torch.Tensor, hi: torch.Tensor, num_queries: int) -> torch.Tensor:
        """Query positional embeddings ``(Q, hidden)`` from farthest-point samples of ``xyz`` (N, 3)."""
        idx = farthest_point_sample(xyz, num_queries)
        return self.query_mlp(self.pos_enc(normalise_coords(xyz[idx], lo, hi)))

    def _predict(self, q: torch.Tensor, mask_feats: torch.Tensor) -> LayerPrediction:
        h = self.out_norm(q)
        return LayerPrediction(objectness=self.objectness(h)[:, 0], masks=mask_feats @ self.mask_embed(h).T)

    def _attn_mask(self, masks: torch.Tensor, level_index: torch.Tensor, n_level: int,
                   keep: torch.Tensor | None) -> torch.Tensor:
        """Boolean ``(Q, K)`` mask (shared by the heads), True = blocked, from the mask logits pooled to the level."""
        prob = masks.detach().sigmoid()
        pooled = prob.new_zeros((n_level, prob.shape[1])).index_add_(0, level_index, prob)
        count = torch.bincount(level_index, minlength=n_level).clamp(min=1).to(prob.dtype)
        pooled = pooled / count[:, None]
        if keep is not None:
            pooled = pooled[keep]
        blocked = (pooled < 0.5).T  # (Q, K)
        blocked[blocked.all(1)] = False
        return blocked

    def forward(self, scene: SceneLevels) -> list[LayerPrediction]:
        """All predictions for one scene: the initial one, then one per layer (the last is final)."""
        q_pos = scene.query_pos
        q = torch.zeros_like(q_pos)
        preds = [self._predict(q, scene.mask_feats)]
        for p in range(self.num_passes):
            for lvl in range(self.num_levels):
                layer = self.layers[lvl if self.shared else p * self.num_levels + lvl]
                keys, k_pos = scene.level_feats[lvl], scene.level_pos[lvl]
                keep = None
                limit = self.sample_sizes[lvl]
                if self.training and keys.shape[0] > limit:
                    keep = torch.randperm(keys.shape[0], device=keys.device)[:limit]
                    keys, k_pos = keys[keep], k_pos[keep]
                mask = self._attn_mask(preds[-1].masks, scene.level_index[lvl], scene.level_feats[lvl].shape[0], keep)
                q = layer(q, q_pos, keys, k_pos, mask)
                preds.append(self._predict(q, scene.mask_feats))
        return preds
