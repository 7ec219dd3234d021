"""Sparse voxel tensors and 3-D convolutions in pure PyTorch (CPU and CUDA, no compiled extension).

A :class:`SparseTensor` holds integer voxel coordinates ``(N, 4) int32`` (batch, x, y, z, in units of
the tensor's own stride) and features ``(N, C)``. Neighbour lookup packs coordinates into ``int64``
keys, sorts them once per coordinate set and finds each kernel offset's neighbours with
``torch.searchsorted``. Convolution is gather -> matmul -> scatter (``index_add_``), one matmul per
kernel offset.

Three operators cover a U-Net:

* :class:`SubMConv3d`  submanifold convolution (stride 1, odd kernel): outputs at the input sites.
* :class:`DownConv3d`  kernel 2, stride 2: outputs at ``unique(coord // 2)``.
* :class:`UpConv3d`    transposed kernel 2, stride 2 onto a known finer coordinate set (the skip's).

Each equals the matching dense ``torch.nn.functional`` operator evaluated at the active sites
(``tests/fast/test_model_sparse.py``). Kernel maps are cached per coordinate set in a dictionary
shared by every tensor derived from the same input, so the 20-odd convolutions of one U-Net level
build their neighbour map once.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from typing import Any

import torch
from torch import nn
from torch.nn import functional as F

from . import spconv_backend

_BITS = 16  # bits per spatial axis in a key (65,536 voxels = 1.3 km at 2 cm)
_MASK = (1 << _BITS) - 1
_HALF = 1 << (_BITS - 1)


#: the convolution kernels a sparse convolution can run on
BACKENDS = ("torch", "spconv")


def use_backend(module: nn.Module, name: str) -> nn.Module:
    """Run every submanifold and transposed convolution inside ``module`` on ``name``'s kernels:
    ``torch`` (pure PyTorch, the default of every new layer) or ``spconv`` (if installed). A
    per-model setting: two models in one process may use different kernels. Returns ``module``."""
    if name not in BACKENDS:
        raise ValueError(f"unknown sparse backend {name!r}; expected 'torch' or 'spconv'")
    if name == "spconv":
        spconv_backend._spconv()
    for m in module.modules():
        if isinstance(m, (SubMConv3d, UpConv3d)):
            m.backend = name
    return module


def encode_keys(coords: torch.Tensor) -> torch.Tensor:
    """Pack ``(N, 4)`` integer coordinates (batch, x, y, z) into ``(N,) int64`` keys.

    Spatial coordinates must lie in ``[-2**15, 2**15)``; the batch index in ``[0, 2**15)``.
    """
    c = coords.to(torch.int64)
    x = (c[:, 1] + _HALF) & _MASK
    y = (c[:, 2] + _HALF) & _MASK
    z = (c[:, 3] + _HALF) & _MASK
    return (c[:, 0] << (3 * _BITS)) | (x << (2 * _BITS)) | (y << _BITS) | z


def kernel_offsets(kernel_size: int, device: torch.device | str = "cpu") -> torch.Tensor:
    """``(k**3, 3) int64`` offsets, z fastest: offset ``i`` matches dense weight ``[..., dx, dy, dz]``."""
    if kernel_size % 2 == 1:
        r = kernel_size // 2
        rng = range(-r, r + 1)
    else:
        rng = range(kernel_size)
    offs = list(itertools.product(rng, rng, rng))
    return torch.tensor(offs, dtype=torch.int64, device=device)


@dataclass
class CoordSet:
    """A coordinate set with its sorted keys and a cache of kernel maps built on it."""

    coords: torch.Tensor  # (N, 4) int32
    keys_sorted: torch.Tensor  # (N,) int64
    order: torch.Tensor  # (N,) int64: keys_sorted = keys[order]
    cache: dict[Any, Any] = field(default_factory=dict)

    @classmethod
    def build(cls, coords: torch.Tensor) -> "CoordSet":
        keys = encode_keys(coords)
        keys_sorted, order = torch.sort(keys)
        return cls(coords=coords, keys_sorted=keys_sorted, order=order)

    def __len__(self) -> int:
        return int(self.coords.shape[0])

    def lookup(self, query_coords: torch.Tensor) -> torch.Tensor:
        """Row index of each query coordinate in this set, ``-1`` where absent; ``(M,) int64``."""
        q = encode_keys(query_coords)
        pos = torch.searchsorted(self.keys_sorted, q)
        pos = pos.clamp(max=max(len(self) - 1, 0))
        if len(self) == 0:
            return torch.full_like(q, -1)
        hit = self.keys_sorted[pos] == q
        return torch.where(hit, self.order[pos], torch.full_like(pos, -1))

    def submanifold_map(self, kernel_size: int) -> list[tuple[torch.Tensor, torch.Tensor] | None]:
        """Per kernel offset, ``(in_rows, out_rows)`` pairs; ``None`` marks the identity (centre) offset."""
        key = ("subm", kernel_size)
        if key not in self.cache:
            offs = kernel_offsets(kernel_size, self.coords.device)
            base = self.coords.to(torch.int64)
            maps: list[tuple[torch.Tensor, torch.Tensor] | None] = []
            for o in offs:
                if bool((o == 0).all()):
                    maps.append(None)
                    continue
                q = base.clone()
                q[:, 1:] += o
                idx = self.lookup(q)
                out_rows = torch.nonzero(idx >= 0).squeeze(1)
                maps.append((idx[out_rows], out_rows))
            self.cache[key] = maps
        return self.cache[key]

    def scene_sizes(self) -> list[int] | None:
        """Rows per scene (batch index ``coords[:, 0]``) when each scene's rows are contiguous and in batch
        order, as in every set the package builds (the batch index is the top of the sort key); else None."""
        key = ("scene_sizes",)
        if key not in self.cache:
            b = self.coords[:, 0].to(torch.int64)
            ordered = len(b) > 0 and bool((b[1:] >= b[:-1]).all())
            self.cache[key] = torch.bincount(b).tolist() if ordered else None
        return self.cache[key]

    def down(self) -> tuple["CoordSet", torch.Tensor, torch.Tensor]:
        """Coarser set ``unique(coord // 2)``; parent row of every row ``(N,)`` and child octant ``(N,)``."""
        key = ("down",)
        if key not in self.cache:
            c = self.coords.to(torch.int64)
            parent = c.clone()
            parent[:, 1:] = torch.div(c[:, 1:], 2, rounding_mode="floor")
            octant = ((c[:, 1] - 2 * parent[:, 1]) * 4 + (c[:, 2] - 2 * parent[:, 2]) * 2
                      + (c[:, 3] - 2 * parent[:, 3]))
            keys = encode_keys(parent)
            ukeys, inverse = torch.unique(keys, sorted=True, return_inverse=True)
            first = torch.full((ukeys.shape[0],), c.shape[0], dtype=torch.int64, device=c.device)
            first.scatter_reduce_(0, inverse, torch.arange(c.shape[0], device=c.device), reduce="amin")
            coarse_coords = parent[first].to(torch.int32)
            coarse = CoordSet(coords=coarse_coords, keys_sorted=ukeys,
                              order=torch.arange(ukeys.shape[0], device=c.device))
            self.cache[key] = (coarse, inverse, octant)
        return self.cache[key]


@dataclass
class SparseTensor:
    """Features ``(N, C)`` on a :class:`CoordSet` at integer stride ``stride`` (voxels of the input grid)."""

    feats: torch.Tensor
    cset: CoordSet
    stride: int = 1

    @property
    def coords(self) -> torch.Tensor:
        return self.cset.coords

    def replace(self, feats: torch.Tensor) -> "SparseTensor":
        return SparseTensor(feats=feats, cset=self.cset, stride=self.stride)


def _init_weight(w: torch.Tensor, fan_in: int) -> None:
    bound = 1.0 / math.sqrt(fan_in)
    nn.init.uniform_(w, -bound, bound)


class SubMConv3d(nn.Module):
    """Submanifold convolution: odd ``kernel_size``, stride 1, outputs at the input sites.

    Weight ``(k**3, C_in, C_out)``; equals ``F.conv3d(padding=k//2)`` on the densified grid read at the
    active sites.
    """

    def __init__(self, in_channels: int, out_channels: int, kernel_size: int = 3, bias: bool = False):
        super().__init__()
        if kernel_size % 2 != 1:
            raise ValueError(f"SubMConv3d needs an odd kernel size, got {kernel_size}")
        self.kernel_size = kernel_size
        self.backend = "torch"  # see use_backend
        self.weight = nn.Parameter(torch.empty(kernel_size ** 3, in_channels, out_channels))
        _init_weight(self.weight, in_channels * kernel_size ** 3)
        self.bias = nn.Parameter(torch.zeros(out_channels)) if bias else None

    def forward(self, x: SparseTensor) -> SparseTensor:
        feats = x.feats
        w = self.weight.to(feats.dtype)
        if self.backend == "spconv":
            out = spconv_backend.subm_conv(x.coords, feats, w, self.kernel_size)
            if self.bias is not None:
                out = out + self.bias.to(out.dtype)
            return x.replace(out)
        maps = x.cset.submanifold_map(self.kernel_size)
        if feats.device.type == "cuda" and torch.is_autocast_enabled("cuda"):
            dt = torch.get_autocast_dtype("cuda")
            feats, w = feats.to(dt), w.to(dt)
        out = _SubMConvFn.apply(feats, w, maps)
        if self.bias is not None:
            out = out + self.bias.to(out.dtype)
        return x.replace(out)


class _SubMConvFn(torch.autograd.Function):
    """Gather-matmul-scatter that saves only its input features for backward.

    Plain autograd would keep every offset's gathered ``(M_o, C_in)`` block alive until backward
    (27 copies of the input for a 3x3x3 kernel); here backward gathers again, so a convolution's
    saved state is one copy of its input.
    """

    @staticmethod
    def forward(ctx, feats: torch.Tensor, weight: torch.Tensor, maps: list) -> torch.Tensor:  # type: ignore[override]
        centre = maps.index(None)
        out = feats @ weight[centre]
        for i, m in enumerate(maps):
            if m is None or m[0].numel() == 0:
                continue
            in_rows, out_rows = m
            out.index_add_(0, out_rows, feats.index_select(0, in_rows) @ weight[i])
        ctx.save_for_backward(feats, weight)
        ctx.maps = maps
        return out

    @staticmethod
    def backward(ctx, grad_out: torch.Tensor):  # type: ignore[override]
        feats, weight_in = ctx.saved_tensors
        maps = ctx.maps
        centre = maps.index(None)
        # autocast may have run the forward matmuls in a lower precision than the inputs: do the
        # backward in the features' dtype and hand each gradient back in its input's dtype
        weight = weight_in.to(feats.dtype)
        grad_out = grad_out.to(feats.dtype).contiguous()
        grad_feats = grad_w = None
        if ctx.needs_input_grad[0]:
            grad_feats = grad_out @ weight[centre].T
        if ctx.needs_input_grad[1]:
            grad_w = torch.zeros_like(weight)
            grad_w[centre] = feats.T @ grad_out
        for i, m in enumerate(maps):
            if m is None or m[0].numel() == 0:
                continue
            in_rows, out_rows = m
            g = grad_out.index_select(0, out_rows)
            if grad_feats is not None:
                grad_feats.index_add_(0, in_rows, g @ weight[i].T)
            if grad_w is not None:
                grad_w[i] = feats.index_select(0, in_rows).T @ g
        if grad_w is not None:
            grad_w = grad_w.to(weight_in.dtype)
        return grad_feats, grad_w, None


class DownConv3d(nn.Module):
    """Kernel 2, stride 2 convolution; output sites ``unique(coord // 2)``. Equals ``F.conv3d(stride=2)``."""

    def __init__(self, in_channels: int, out_channels: int, bias: bool = False):
        super().__init__()
        self.weight = nn.Parameter(torch.empty(8, in_channels, out_channels))
        _init_weight(self.weight, in_channels * 8)
        self.bias = nn.Parameter(torch.zeros(out_channels)) if bias else None

    def forward(self, x: SparseTensor) -> SparseTensor:
        coarse, inverse, octant = x.cset.down()
        w = self.weight.to(x.feats.dtype)
        # One batched matmul over the 8 octants: (N, C_in) x (C_in, C_out) per row's octant, grouped.
        rows = [torch.nonzero(octant == o).squeeze(1) for o in range(8)]
        src = torch.cat([x.feats.index_select(0, r) @ w[o] for o, r in enumerate(rows)])
        out = src.new_zeros((len(coarse), w.shape[2])).index_add(0, inverse[torch.cat(rows)], src)
        if self.bias is not None:
            out = out + self.bias.to(out.dtype)
        return SparseTensor(feats=out, cset=coarse, stride=x.stride * 2)


class UpConv3d(nn.Module):
    """Transposed kernel 2, stride 2 convolution onto the finer coordinate set ``target``.

    Every fine site has exactly one parent, so this is a per-octant gather-matmul; it equals
    ``F.conv_transpose3d(stride=2)`` read at the fine sites.
    """

    def __init__(self, in_channels: int, out_channels: int, bias: bool = False):
        super().__init__()
        self.backend = "torch"  # see use_backend
        self.weight = nn.Parameter(torch.empty(8, in_channels, out_channels))
        _init_weight(self.weight, in_channels)
        self.bias = nn.Parameter(torch.zeros(out_channels)) if bias else None

    def forward(self, x: SparseTensor, target: SparseTensor) -> SparseTensor:
        coarse, inverse, octant = target.cset.down()
        if x.cset is not coarse:
            raise ValueError("UpConv3d: the input is not the stride-2 parent of the target coordinates")
        w = self.weight.to(x.feats.dtype)
        if self.backend == "spconv":
            sites, feats = spconv_backend.up_conv(x.coords, x.feats, w)
            rows = CoordSet.build(sites).lookup(target.coords)
            if bool((rows < 0).any()):
                raise RuntimeError("spconv's transposed conv missed target sites")
            out = feats[rows]
            if self.bias is not None:
                out = out + self.bias.to(out.dtype)
            return SparseTensor(feats=out, cset=target.cset, stride=target.stride)
        rows = [torch.nonzero(octant == o).squeeze(1) for o in range(8)]
        src = torch.cat([x.feats.index_select(0, inverse[r]) @ w[o] for o, r in enumerate(rows)])
        out = src.new_zeros((len(target.cset), w.shape[2])).index_copy(0, torch.cat(rows), src)
        if self.bias is not None:
            out = out + self.bias.to(out.dtype)
        return SparseTensor(feats=out, cset=target.cset, stride=target.stride)


class SparseBatchNorm(nn.BatchNorm1d):
    """BatchNorm over the active sites' features."""

    def forward(self, x: SparseTensor) -> SparseTensor:  # type: ignore[override]
        return x.replace(super().forward(x.feats))


class SparseSceneNorm(nn.Module):
    """Normalisation by each scene's own statistics (batch index = ``coords[:, 0]``), with an affine map.

    Unlike BatchNorm it keeps no running statistics, so training and inference compute the same
    function: a model trained on generated scans is not tied to their feature statistics.
    """

    def __init__(self, channels: int, eps: float = 1e-5):
        super().__init__()
        self.eps = eps
        self.weight = nn.Parameter(torch.ones(channels))
        self.bias = nn.Parameter(torch.zeros(channels))

    def forward(self, x: SparseTensor) -> SparseTensor:
        f = x.feats
        # Scenes in contiguous rows (known once per coordinate set): each scene is one call of the fused
        # batch-norm kernel in training mode without running statistics, which is this normalisation
        # (biased variance) at a fraction of the general path's time (docs/fidelity.md, "Cost").
        sizes = x.cset.scene_sizes()
        if sizes is not None and min(s for s in sizes if s) > 1:  # batch_norm refuses a single row
            parts = [F.batch_norm(p, None, None, self.weight, self.bias, True, 0.0, self.eps)
                     for p in f.split(sizes) if len(p)]
            return x.replace(parts[0] if len(parts) == 1 else torch.cat(parts))
        return x.replace(self.reference(f, x.coords[:, 0].to(torch.int64)))

    def reference(self, f: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
        """The normalisation for rows in any order: per-scene mean and biased variance by scatter-adds."""
        nb = int(b.max()) + 1 if len(b) else 1
        counts = torch.bincount(b, minlength=nb).clamp(min=1).to(f.dtype)[:, None]
        mean = f.new_zeros((nb, f.shape[1])).index_add(0, b, f) / counts
        centred = f - mean[b]
        var = f.new_zeros((nb, f.shape[1])).index_add(0, b, centred * centred) / counts
        return centred * torch.rsqrt(var[b] + self.eps) * self.weight + self.bias


class SparseReLU(nn.Module):
    def forward(self, x: SparseTensor) -> SparseTensor:
        return x.replace(torch.relu(x.feats))


class SparseLinear(nn.Linear):
    """A 1x1x1 convolution."""

    def forward(self, x: SparseTensor) -> SparseTensor:  # type: ignore[override]
        return x.replace(super().forward(x.feats))


def sparse_tensor(coords: torch.Tensor, feats: torch.Tensor) -> SparseTensor:
    """Build a stride-1 :class:`SparseTensor` from unique ``(N, 4) int32`` coordinates and ``(N, C)`` features."""
    if coords.ndim != 2 or coords.shape[1] != 4:
        raise ValueError(f"coords must be (N, 4) (batch, x, y, z), got {tuple(coords.shape)}")
    if feats.shape[0] != coords.shape[0]:
        raise ValueError(f"{feats.shape[0]} feature rows for {coords.shape[0]} coordinates")
    return SparseTensor(feats=feats, cset=CoordSet.build(coords.to(torch.int32)))
