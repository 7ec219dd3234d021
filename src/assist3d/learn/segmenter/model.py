"""The segmenter network: a sparse residual U-Net with a foreground head and a centre-offset head.

PointGroup-style bottom-up design, chosen because it trains on 2 CPU cores (experiments/fidelity-log.md): dense
per-voxel targets give every voxel a gradient from the first step, where a mask-query decoder
(Mask3D) needs hundreds of epochs before its masks carry any signal.
"""

from __future__ import annotations

import torch
from torch import nn

from ..models.registry import MODELS
from ..models.sparse import SparseTensor, sparse_tensor
from ..models.unet import SparseUNet, make_norm
from .config import NetConfig
from .features import num_channels


class _Head(nn.Module):
    def __init__(self, cin: int, cout: int, norm: str):
        super().__init__()
        self.fc1 = nn.Linear(cin, cin)
        self.norm = make_norm(norm, cin, 0.1)
        self.fc2 = nn.Linear(cin, cout)

    def forward(self, x: SparseTensor) -> torch.Tensor:
        y = self.norm(x.replace(self.fc1(x.feats)))
        return self.fc2(torch.relu(y.feats))


@MODELS.register("segmenter")
class Segmenter(nn.Module):
    """``forward(coords (V, 4) int32 [batch, x, y, z], feats (V, C))`` -> (fg logit (V,), offset (V, 3) m)."""

    def __init__(self, cfg: NetConfig):
        super().__init__()
        self.cfg = cfg
        self.backbone = SparseUNet(in_channels=num_channels(cfg.use_color), stem_channels=cfg.stem_channels,
                                   stem_kernel=3, enc_channels=cfg.enc_channels, enc_blocks=cfg.enc_blocks,
                                   dec_channels=cfg.dec_channels, dec_blocks=cfg.dec_blocks, norm=cfg.norm,
                                   bn_momentum=0.1)
        c = self.backbone.out_channels
        self.fg_head = _Head(c, 1, cfg.norm)
        self.offset_head = _Head(c, 3, cfg.norm)

    def forward(self, coords: torch.Tensor, feats: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        x = sparse_tensor(coords, feats)
        full = self.backbone(x).full
        return self.fg_head(full).squeeze(1), self.offset_head(full)


class SegmenterEnsemble(nn.Module):
    """Several trained segmenters as one: the same ``forward`` as :class:`Segmenter`, returning the
    logit of the members' mean foreground probability and their mean offset. Members must share the
    input features (voxel size and colour use); experiments/fidelity-log.md ("Seed ensembles") measures it."""

    PROB_EPS = 1e-6  # keeps the logit of a mean probability of exactly 0 or 1 finite

    def __init__(self, members: list[Segmenter]):
        super().__init__()
        if not members:
            raise ValueError("an ensemble needs at least one segmenter")
        self.members = nn.ModuleList(members)

    def forward(self, coords: torch.Tensor, feats: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        outs = [m(coords, feats) for m in self.members]
        prob = torch.stack([torch.sigmoid(logit) for logit, _ in outs]).mean(0)
        return torch.logit(prob, eps=self.PROB_EPS), torch.stack([off for _, off in outs]).mean(0)


Network = Segmenter | SegmenterEnsemble


def count_parameters(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
