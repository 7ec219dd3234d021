"""A Res16UNet34C-like sparse residual U-Net (the Mask3D backbone) on :mod:`assist3d.learn.models.sparse`.

Layout (paper defaults): stem submanifold conv k=5 -> 32; four encoder stages, each a kernel-2
stride-2 conv then ``enc_blocks[i]`` BasicBlocks with ``enc_channels[i]`` channels (2, 3, 4, 6 blocks;
32, 64, 128, 256 channels); four decoder stages, each a kernel-2 stride-2 transposed conv, concatenation
with the encoder skip and ``dec_blocks[i]`` BasicBlocks with ``dec_channels[i]`` channels (2, 2, 2, 2;
256, 128, 96, 96). BatchNorm momentum 0.02. ``norm="scene"`` swaps every BatchNorm for a per-scene
normalisation (used by the CPU segmenter, :mod:`assist3d.learn.segmenter`).

:meth:`SparseUNet.forward` returns the feature pyramid for the transformer decoder: the bottleneck
(stride 16) and the first three decoder outputs (strides 8, 4, 2), plus the full-resolution output
(stride 1) used for masks.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import nn

from .sparse import (DownConv3d, SparseBatchNorm, SparseLinear, SparseReLU, SparseSceneNorm, SparseTensor,
                     SubMConv3d, UpConv3d)


def make_norm(kind: str, channels: int, bn_momentum: float) -> nn.Module:
    """``batch``: BatchNorm with running statistics (Mask3D); ``scene``: statistics of each scene, the
    same in training and inference (:class:`SparseSceneNorm`)."""
    if kind == "batch":
        return SparseBatchNorm(channels, momentum=bn_momentum)
    if kind == "scene":
        return SparseSceneNorm(channels)
    raise ValueError(f"unknown norm {kind!r}; expected 'batch' or 'scene'")


class BasicBlock(nn.Module):
    """Two 3x3x3 submanifold convs with BatchNorm and a residual (1x1 projection when channels change)."""

    def __init__(self, cin: int, cout: int, bn_momentum: float, norm: str = "batch"):
        super().__init__()
        self.conv1 = SubMConv3d(cin, cout, 3)
        self.bn1 = make_norm(norm, cout, bn_momentum)
        self.conv2 = SubMConv3d(cout, cout, 3)
        self.bn2 = make_norm(norm, cout, bn_momentum)
        self.relu = SparseReLU()
        self.proj: nn.Module | None = None
        if cin != cout:
            self.proj = nn.Sequential(SparseLinear(cin, cout, bias=False), make_norm(norm, cout, bn_momentum))

    def forward(self, x: SparseTensor) -> SparseTensor:
        res = x if self.proj is None else self.proj(x)
        y = self.relu(self.bn1(self.conv1(x)))
        y = self.bn2(self.conv2(y))
        return y.replace(torch.relu(y.feats + res.feats))


def _blocks(cin: int, cout: int, n: int, bn_momentum: float, norm: str = "batch") -> nn.Sequential:
    layers = [BasicBlock(cin, cout, bn_momentum, norm)]
    layers += [BasicBlock(cout, cout, bn_momentum, norm) for _ in range(n - 1)]
    return nn.Sequential(*layers)


@dataclass
class UNetOutput:
    """``levels``: features at strides 16, 8, 4, 2 (coarse to fine); ``full``: stride-1 features."""

    levels: list[SparseTensor]
    full: SparseTensor


class SparseUNet(nn.Module):
    def __init__(self, in_channels: int = 3, stem_channels: int = 32, stem_kernel: int = 5,
                 enc_channels: tuple[int, ...] = (32, 64, 128, 256), enc_blocks: tuple[int, ...] = (2, 3, 4, 6),
                 dec_channels: tuple[int, ...] = (256, 128, 96, 96), dec_blocks: tuple[int, ...] = (2, 2, 2, 2),
                 bn_momentum: float = 0.02, norm: str = "batch"):
        super().__init__()
        if not (len(enc_channels) == len(enc_blocks) == len(dec_channels) == len(dec_blocks) == 4):
            raise ValueError("the U-Net has exactly 4 encoder and 4 decoder stages")
        self.stem = nn.Sequential(SubMConv3d(in_channels, stem_channels, stem_kernel),
                                  make_norm(norm, stem_channels, bn_momentum), SparseReLU())
        self.downs = nn.ModuleList()
        self.down_bns = nn.ModuleList()
        self.enc = nn.ModuleList()
        c = stem_channels
        skips = [stem_channels]
        for ch, nb in zip(enc_channels, enc_blocks):
            self.downs.append(DownConv3d(c, c))
            self.down_bns.append(nn.Sequential(make_norm(norm, c, bn_momentum), SparseReLU()))
            self.enc.append(_blocks(c, ch, nb, bn_momentum, norm))
            c = ch
            skips.append(ch)
        self.ups = nn.ModuleList()
        self.up_bns = nn.ModuleList()
        self.dec = nn.ModuleList()
        for i, (ch, nb) in enumerate(zip(dec_channels, dec_blocks)):
            skip_c = skips[3 - i]
            self.ups.append(UpConv3d(c, ch))
            self.up_bns.append(nn.Sequential(make_norm(norm, ch, bn_momentum), SparseReLU()))
            self.dec.append(_blocks(ch + skip_c, ch, nb, bn_momentum, norm))
            c = ch
        self.level_channels = [enc_channels[-1], *dec_channels[:3]]
        self.out_channels = dec_channels[-1]

    def forward(self, x: SparseTensor) -> UNetOutput:
        y = self.stem(x)
        skips = [y]
        for down, bn, enc in zip(self.downs, self.down_bns, self.enc):
            y = enc(bn(down(y)))
            skips.append(y)
        levels = [y]
        for i, (up, bn, dec) in enumerate(zip(self.ups, self.up_bns, self.dec)):
            skip = skips[3 - i]
            y = bn(up(y, skip))
            y = dec(y.replace(torch.cat([y.feats, skip.feats], 1)))
            if i < 3:
                levels.append(y)
        return UNetOutput(levels=levels, full=y)
