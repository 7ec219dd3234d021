"""The class-agnostic Mask3D-style model: sparse U-Net backbone + transformer mask decoder.

Input: a batch of voxelised scenes concatenated (see :func:`assist3d.learn.engine.voxelize.collate`):
``coords`` (N, 4) int32 (batch, x, y, z voxel indices, rows sorted by batch), ``feats`` (N, C) float
(normalised RGB), ``batch_size``. Output: per scene, the list of :class:`LayerPrediction` (initial
queries, then after every decoder layer; the last one is the final prediction), masks over that
scene's voxels in input row order.
"""

from __future__ import annotations

import torch
from torch import nn

from .decoder import LayerPrediction, MaskDecoder, SceneLevels
from .registry import MODELS
from .sparse import sparse_tensor, use_backend
from .unet import SparseUNet


class Mask3D(nn.Module):
    def __init__(self, *, in_channels: int = 3, stem_channels: int = 32, stem_kernel: int = 5,
                 enc_channels: tuple[int, ...] = (32, 64, 128, 256), enc_blocks: tuple[int, ...] = (2, 3, 4, 6),
                 dec_channels: tuple[int, ...] = (256, 128, 96, 96), dec_blocks: tuple[int, ...] = (2, 2, 2, 2),
                 bn_momentum: float = 0.02, hidden: int = 128, heads: int = 8, ffn: int = 1024,
                 dropout: float = 0.0, num_passes: int = 3, shared: bool = True,
                 sample_sizes: tuple[int, ...] = (200, 800, 3200, 12800),
                 num_queries: int = 100, num_queries_eval: int = 150):
        super().__init__()
        self.backbone = SparseUNet(in_channels, stem_channels, stem_kernel, tuple(enc_channels), tuple(enc_blocks),
                                   tuple(dec_channels), tuple(dec_blocks), bn_momentum)
        self.decoder = MaskDecoder(self.backbone.level_channels, self.backbone.out_channels, hidden, heads, ffn,
                                   dropout, num_passes, shared, tuple(sample_sizes))
        self.num_queries = num_queries
        self.num_queries_eval = num_queries_eval

    def forward(self, coords: torch.Tensor, feats: torch.Tensor, batch_size: int) -> list[list[LayerPrediction]]:
        x = sparse_tensor(coords, feats)
        out = self.backbone(x)
        num_q = self.num_queries if self.training else self.num_queries_eval
        full = out.full
        full_rows = _batch_ranges(full.coords, batch_size)
        # level row of every full-resolution voxel, composed through the stride-2 maps
        level_index: dict[int, torch.Tensor] = {}
        cur = full.cset
        idx = torch.arange(len(cur), device=coords.device)
        stride = 1
        while stride < max(lv.stride for lv in out.levels):
            coarse, inverse, _ = cur.down()
            idx = inverse[idx]
            cur = coarse
            stride *= 2
            level_index[stride] = idx
        mask_feats = self.decoder.mask_proj(full.feats)
        level_feats = [proj(lv.feats) for proj, lv in zip(self.decoder.level_proj, out.levels)]
        results: list[list[LayerPrediction]] = []
        for b in range(batch_size):
            s, e = full_rows[b]
            xyz = full.coords[s:e, 1:].float()  # float32 even under autocast: voxel indices reach the hundreds
            lo, hi = xyz.min(0).values, xyz.max(0).values + 1
            lfeats, lpos, lidx = [], [], []
            for lv, f in zip(out.levels, level_feats):
                ls, le = _batch_ranges(lv.coords, batch_size)[b]
                centre = (lv.coords[ls:le, 1:].to(xyz.dtype) + 0.5) * lv.stride
                lfeats.append(f[ls:le])
                lpos.append(self.decoder.pos_enc((centre - lo) / (hi - lo).clamp(min=1e-6)).to(f.dtype))
                lidx.append(level_index[lv.stride][s:e] - ls)
            scene = SceneLevels(level_feats=lfeats, level_pos=lpos, level_index=lidx, mask_feats=mask_feats[s:e],
                                query_pos=self.decoder.queries(xyz + 0.5, lo, hi, num_q).to(mask_feats.dtype))
            results.append(self.decoder(scene))
        return results


def _batch_ranges(coords: torch.Tensor, batch_size: int) -> list[tuple[int, int]]:
    """Row range of each batch index in ``coords`` (rows sorted by batch)."""
    b = coords[:, 0].contiguous().to(torch.int64)
    edges = torch.searchsorted(b, torch.arange(batch_size + 1, device=b.device)).tolist()
    return [(edges[i], edges[i + 1]) for i in range(batch_size)]


@MODELS.register("mask3d")
def build_mask3d(cfg) -> Mask3D:
    """The Mask3D-style model from a training config's ``model`` section (``ModelConfig``), on its
    ``backend``'s sparse convolution kernels."""
    kwargs = cfg.model_dump()
    backend = kwargs.pop("backend")
    return use_backend(Mask3D(**kwargs), backend)
