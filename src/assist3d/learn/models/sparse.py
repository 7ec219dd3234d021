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
(``tests/fast/test_learn_models_sparse.py``). Kernel maps are cached per coordinate set in a dictionary
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


#: Precisions the sparse convolutions can compute in (:func:`use_precision`).
PRECISIONS = ("float32", "bfloat16")


def use_precision(module: nn.Module, name: str) -> nn.Module:
    """Compute every sparse convolution inside ``module`` in ``name``: ``float32`` (the per-offset
    gather-matmul-scatter, the default of every new layer) or ``bfloat16`` (im2col blocks with
    bfloat16 inputs and float32 accumulation; inputs, outputs and gradients stay float32, and every
    other layer is untouched). A per-model setting, like :func:`use_backend`. Returns ``module``."""
    if name not in PRECISIONS:
        raise ValueError(f"unknown precision {name!r}; expected one of {', '.join(PRECISIONS)}")
    dtype = None if name == "float32" else torch.bfloat16
    for m in module.modules():
        if isinstance(m, (SubMConv3d, DownConv3d, UpConv3d)):
            m.compute_dtype = dtype
    return module


def native_bfloat16(device: str | torch.device = "cpu") -> bool:
    """Whether ``device`` multiplies bfloat16 matrices in hardware: a CPU with AMX or AVX-512 BF16
    (as PyTorch's oneDNN sees it). CUDA devices answer False here: the im2col path is measured on
    CPUs only."""
    if torch.device(device).type != "cpu":
        return False
    check = getattr(torch.ops.mkldnn, "_is_mkldnn_bf16_supported", None)
    try:
        return bool(check()) if check is not None else False
    except RuntimeError:
        return False


def resolve_precision(name: str, device: str | torch.device = "cpu") -> str:
    """``auto`` -> ``bfloat16`` where :func:`native_bfloat16`, else ``float32``; others unchanged."""
    if name == "auto":
        return "bfloat16" if native_bfloat16(device) else "float32"
    if name not in PRECISIONS:
        raise ValueError(f"unknown precision {name!r}; expected auto or one of {', '.join(PRECISIONS)}")
    return name


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
        """Per kernel offset, ``(in_rows, out_rows)`` pairs; ``None`` marks the identity (centre) offset.

        ``out_rows`` ascending. Read off the dense-grid neighbour table (:meth:`neighbour_table`) when the
        scenes' bounding boxes are small enough for it, else one sorted-key search per offset: the same maps
        either way, the table being several times cheaper than 26 searches."""
        key = ("subm", kernel_size)
        if key not in self.cache:
            table = self.cache.get(("table", kernel_size))
            if table is None:
                table = _dense_neighbour_table(self, kernel_size)  # not kept: the maps are
            self.cache[key] = (_maps_of_table(table, len(self)) if table is not None
                               else _searched_maps(self, kernel_size))
        return self.cache[key]

    def neighbour_table(self, kernel_size: int) -> torch.Tensor:
        """``(N, k**3) int64``: row of each site's neighbour at every kernel offset (the order of
        :func:`kernel_offsets`), ``N`` where there is none (the zero row the im2col path appends).

        Built by one lookup per site and offset in a dense index grid per scene when the scenes'
        bounding boxes are small enough (:data:`DENSE_GRID_CELLS`), else by the sorted-key search."""
        key = ("table", kernel_size)
        if key not in self.cache:
            self.cache[key] = _neighbour_table(self, kernel_size)
        return self.cache[key]

    def children(self) -> tuple[torch.Tensor, torch.Tensor]:
        """For the coarser set of :meth:`down`: ``(M, 8) int64`` row of each coarse site's child in each
        octant (``N`` where absent) and ``(N,) int64`` ``parent * 8 + octant`` of every row."""
        key = ("children",)
        if key not in self.cache:
            coarse, inverse, octant = self.down()
            n = len(self)
            table = torch.full((len(coarse) * 8,), n, dtype=torch.int64, device=self.coords.device)
            pick = inverse * 8 + octant
            table[pick] = torch.arange(n, device=self.coords.device)
            self.cache[key] = (table.view(-1, 8), pick)
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


#: The largest dense index grid (cells, all scenes together) a neighbour table is built in; past it
#: the table comes from the sorted-key search (same result, more time).
DENSE_GRID_CELLS = 32_000_000  # 128 MB of int32


def _searched_maps(cset: "CoordSet", kernel_size: int) -> list[tuple[torch.Tensor, torch.Tensor] | None]:
    """:meth:`CoordSet.submanifold_map` by one sorted-key search per offset (any extent)."""
    offs = kernel_offsets(kernel_size, cset.coords.device)
    base = cset.coords.to(torch.int64)
    maps: list[tuple[torch.Tensor, torch.Tensor] | None] = []
    for o in offs:
        if bool((o == 0).all()):
            maps.append(None)
            continue
        q = base.clone()
        q[:, 1:] += o
        idx = cset.lookup(q)
        out_rows = torch.nonzero(idx >= 0).squeeze(1)
        maps.append((idx[out_rows], out_rows))
    return maps


def _maps_of_table(table: torch.Tensor, n: int) -> list[tuple[torch.Tensor, torch.Tensor] | None]:
    """:meth:`CoordSet.submanifold_map` read off a neighbour table ``(n, k**3)`` (``n`` = none)."""
    centre = table.shape[1] // 2
    maps: list[tuple[torch.Tensor, torch.Tensor] | None] = []
    for o, col in enumerate(table.T.contiguous()):
        if o == centre:
            maps.append(None)
            continue
        out_rows = torch.nonzero(col < n).squeeze(1)
        maps.append((col[out_rows], out_rows))
    return maps


def _dense_neighbour_table(cset: "CoordSet", kernel_size: int) -> torch.Tensor | None:
    """The neighbour table of :meth:`CoordSet.neighbour_table` by one lookup per site and offset in a dense
    index grid per scene, padded by the kernel radius; None when the grid would exceed
    :data:`DENSE_GRID_CELLS` cells."""
    coords = cset.coords
    n = coords.shape[0]
    offs = kernel_offsets(kernel_size, coords.device)
    if n == 0:
        return torch.zeros((0, len(offs)), dtype=torch.int64, device=coords.device)
    c = coords.to(torch.int64)
    r = kernel_size // 2
    lo = c[:, 1:].amin(0) - r
    ext = c[:, 1:].amax(0) + r + 1 - lo
    cells = (int(c[:, 0].max()) + 1) * int(ext.prod())
    if cells > DENSE_GRID_CELLS:
        return None
    # a dense grid of row indices (n = empty): every query is in range
    strides = torch.stack([ext[1] * ext[2], ext[2], torch.ones_like(ext[2])])
    grid = torch.full((cells,), n, dtype=torch.int32, device=coords.device)
    flat = c[:, 0] * int(ext.prod()) + ((c[:, 1:] - lo) * strides).sum(1)
    grid[flat] = torch.arange(n, dtype=torch.int32, device=coords.device)
    return grid[flat[:, None] + (offs * strides).sum(1)[None, :]].to(torch.int64)


def _neighbour_table(cset: "CoordSet", kernel_size: int) -> torch.Tensor:
    table = _dense_neighbour_table(cset, kernel_size)
    if table is not None:
        return table
    # past the dense grid's size: the per-offset kernel map (sorted-key search) laid out as a table
    n = len(cset)
    table = torch.full((n, kernel_size ** 3), n, dtype=torch.int64, device=cset.coords.device)
    for o, m in enumerate(cset.submanifold_map(kernel_size)):
        if m is None:
            table[:, o] = torch.arange(n, device=cset.coords.device)
        else:
            table[m[1], o] = m[0]
    return table


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
        self.compute_dtype: torch.dtype | None = None  # see use_precision
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
        if self.compute_dtype is not None:
            out = _SubMConvIm2colFn.apply(feats, w, x.cset.neighbour_table(self.kernel_size), self.compute_dtype)
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


#: Rows of one im2col block: the gathered ``(rows, k**3 * C)`` matrix stays a few MB.
IM2COL_ROWS = 4096
#: Row counts a reduced-precision matmul is padded to. oneDNN builds a kernel for every new matrix
#: shape (several ms each), and scenes give every layer a new row count each step: padding rows to
#: one of a few sizes lets each layer reuse the same few kernels for the whole run.
_ROW_BUCKETS = (256, 1024, IM2COL_ROWS)


def _bucket(n: int) -> int:
    """The padded row count of a block of ``n <= IM2COL_ROWS`` rows."""
    for b in _ROW_BUCKETS:
        if n <= b:
            return b
    return IM2COL_ROWS


def _blocks(n: int):
    """``(start, rows, padded rows)`` of each block of ``n`` rows."""
    for r in range(0, n, IM2COL_ROWS):
        m = min(IM2COL_ROWS, n - r)
        yield r, m, _bucket(m)


def _with_zero_row(t: torch.Tensor) -> torch.Tensor:
    return torch.cat([t, t.new_zeros(1, t.shape[1])])


def _pad_rows(t: torch.Tensor, rows: int, fill: int | float = 0) -> torch.Tensor:
    if t.shape[0] == rows:
        return t
    return torch.cat([t, t.new_full((rows - t.shape[0], *t.shape[1:]), fill)])


def gather_mm(src: torch.Tensor, table: torch.Tensor, w: torch.Tensor) -> torch.Tensor:
    """``out[i] = concat_j(src[table[i, j]]) @ w`` for a ``(n, k)`` index ``table`` into ``src`` (whose
    last row is zeros: the index of "no neighbour"), ``w`` of shape ``(k * C, C_out)``; block by block
    so the gathered matrix stays small, every block padded to a bucketed row count."""
    n, k = table.shape
    c = src.shape[1]
    out = src.new_empty((n, w.shape[1]))
    zero = src.shape[0] - 1
    for r, m, rows in _blocks(n):
        idx = _pad_rows(table[r:r + m], rows, zero).reshape(-1)
        out[r:r + m] = (src.index_select(0, idx).view(rows, k * c) @ w)[:m]
    return out


def gather_tmm(src: torch.Tensor, table: torch.Tensor, g: torch.Tensor) -> torch.Tensor:
    """``concat_j(src[table[:, j]]).T @ g`` as float32 ``(k * C, C_g)``: the weight gradient of
    :func:`gather_mm` for the output gradient ``g`` ``(n, C_g)``."""
    n, k = table.shape
    c = src.shape[1]
    acc = torch.zeros((k * c, g.shape[1]), dtype=torch.promote_types(src.dtype, torch.float32), device=src.device)
    zero = src.shape[0] - 1
    for r, m, rows in _blocks(n):
        idx = _pad_rows(table[r:r + m], rows, zero).reshape(-1)
        cols = src.index_select(0, idx).view(rows, k * c)
        acc += (cols.T @ _pad_rows(g[r:r + m], rows)).to(acc.dtype)
    return acc


def rows_mm(a: torch.Tensor, w: torch.Tensor) -> torch.Tensor:
    """``a @ w`` block by block with bucketed row counts (see :data:`_ROW_BUCKETS`)."""
    n = a.shape[0]
    out = a.new_empty((n, w.shape[1]))
    for r, m, rows in _blocks(n):
        out[r:r + m] = (_pad_rows(a[r:r + m], rows) @ w)[:m]
    return out


def _save_reduced(ctx, feats: torch.Tensor, weight: torch.Tensor, tables: tuple[torch.Tensor, ...],
                  dtype: torch.dtype) -> tuple[torch.Tensor, torch.Tensor]:
    """Features and weight in ``dtype``, saved for backward with the index ``tables``; the input dtypes
    are kept on ``ctx`` so that the gradients come back in them."""
    f, w = feats.to(dtype), weight.to(dtype)
    ctx.save_for_backward(f, w, *tables)
    ctx.in_dtypes = (feats.dtype, weight.dtype)
    return f, w


class _SubMConvIm2colFn(torch.autograd.Function):
    """The submanifold convolution as im2col (:func:`gather_mm` over the neighbour table): one large
    matmul per block of sites instead of one small matmul and one scatter per kernel offset. The input
    gradient is the same operation on the output gradient with the kernel mirrored (the neighbour of
    ``j`` at offset ``-o`` is the site whose neighbour at ``o`` is ``j``), so neither direction scatters.

    Computes in ``dtype`` with float32 accumulation and returns features in the input's dtype. It does
    up to ``k**3 / mean neighbours`` times the multiply-adds of the per-offset path, which pays where
    the large matmul runs on matrix units (bf16 on AMX or AVX-512) and the per-offset path is bound by
    its gathers and scatters.
    """

    @staticmethod
    def forward(ctx, feats: torch.Tensor, weight: torch.Tensor, table: torch.Tensor,  # type: ignore[override]
                dtype: torch.dtype) -> torch.Tensor:
        k3, cin, cout = weight.shape
        f, w = _save_reduced(ctx, feats, weight, (table,), dtype)
        return gather_mm(_with_zero_row(f), table, w.reshape(k3 * cin, cout)).to(feats.dtype)

    @staticmethod
    def backward(ctx, grad_out: torch.Tensor):  # type: ignore[override]
        f, w, table = ctx.saved_tensors
        k3, cin, cout = w.shape
        g = grad_out.to(f.dtype)
        grad_f = grad_w = None
        if ctx.needs_input_grad[0]:
            mirrored = w.flip(0).transpose(1, 2).reshape(k3 * cout, cin)
            grad_f = gather_mm(_with_zero_row(g), table, mirrored).to(ctx.in_dtypes[0])
        if ctx.needs_input_grad[1]:
            grad_w = gather_tmm(_with_zero_row(f), table, g).view(k3, cin, cout).to(ctx.in_dtypes[1])
        return grad_f, grad_w, None, None


class _DownConvIm2colFn(torch.autograd.Function):
    """Kernel-2 stride-2 convolution as im2col over each coarse site's 8 children (``children``
    ``(M, 8)``, row ``N`` where a child is absent; ``pick`` ``(N,)`` = parent * 8 + octant of every
    fine row). Weight ``(8, C_in, C_out)``."""

    @staticmethod
    def forward(ctx, feats, weight, children, pick, dtype):  # type: ignore[override]
        _, cin, cout = weight.shape
        f, w = _save_reduced(ctx, feats, weight, (children, pick), dtype)
        return gather_mm(_with_zero_row(f), children, w.reshape(8 * cin, cout)).to(feats.dtype)

    @staticmethod
    def backward(ctx, grad_out):  # type: ignore[override]
        f, w, children, pick = ctx.saved_tensors
        _, cin, cout = w.shape
        g = grad_out.to(f.dtype)
        grad_f = grad_w = None
        if ctx.needs_input_grad[0]:
            per_child = rows_mm(g, w.reshape(8 * cin, cout).T.contiguous())  # (M, 8 * C_in)
            grad_f = per_child.view(-1, cin).index_select(0, pick).to(ctx.in_dtypes[0])
        if ctx.needs_input_grad[1]:
            grad_w = gather_tmm(_with_zero_row(f), children, g).view(8, cin, cout).to(ctx.in_dtypes[1])
        return grad_f, grad_w, None, None, None


class _UpConvIm2colFn(torch.autograd.Function):
    """Transposed kernel-2 stride-2 convolution onto the fine sites: every coarse site's 8 possible
    children at once (one matmul with the weight as ``(C_in, 8 * C_out)``), then each fine site reads
    its own (``pick``); the transpose of :class:`_DownConvIm2colFn`."""

    @staticmethod
    def forward(ctx, feats, weight, children, pick, dtype):  # type: ignore[override]
        _, cin, cout = weight.shape
        f, w = _save_reduced(ctx, feats, weight, (children, pick), dtype)
        every = rows_mm(f, w.permute(1, 0, 2).reshape(cin, 8 * cout))  # (M, 8 * C_out)
        return every.view(-1, cout).index_select(0, pick).to(feats.dtype)

    @staticmethod
    def backward(ctx, grad_out):  # type: ignore[override]
        f, w, children, pick = ctx.saved_tensors
        _, cin, cout = w.shape
        g = _with_zero_row(grad_out.to(f.dtype))
        grad_f = grad_w = None
        if ctx.needs_input_grad[0]:
            grad_f = gather_mm(g, children, w.transpose(1, 2).reshape(8 * cout, cin)).to(ctx.in_dtypes[0])
        if ctx.needs_input_grad[1]:
            gw = gather_tmm(g, children, f)  # (8 * C_out, C_in)
            grad_w = gw.view(8, cout, cin).transpose(1, 2).contiguous().to(ctx.in_dtypes[1])
        return grad_f, grad_w, None, None, None


class DownConv3d(nn.Module):
    """Kernel 2, stride 2 convolution; output sites ``unique(coord // 2)``. Equals ``F.conv3d(stride=2)``."""

    def __init__(self, in_channels: int, out_channels: int, bias: bool = False):
        super().__init__()
        self.weight = nn.Parameter(torch.empty(8, in_channels, out_channels))
        _init_weight(self.weight, in_channels * 8)
        self.compute_dtype: torch.dtype | None = None  # see use_precision
        self.bias = nn.Parameter(torch.zeros(out_channels)) if bias else None

    def forward(self, x: SparseTensor) -> SparseTensor:
        coarse, inverse, octant = x.cset.down()
        if self.compute_dtype is not None:
            children, pick = x.cset.children()
            out = _DownConvIm2colFn.apply(x.feats, self.weight, children, pick, self.compute_dtype)
            if self.bias is not None:
                out = out + self.bias.to(out.dtype)
            return SparseTensor(feats=out, cset=coarse, stride=x.stride * 2)
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
        self.compute_dtype: torch.dtype | None = None  # see use_precision
        self.bias = nn.Parameter(torch.zeros(out_channels)) if bias else None

    def forward(self, x: SparseTensor, target: SparseTensor) -> SparseTensor:
        coarse, inverse, octant = target.cset.down()
        if x.cset is not coarse:
            raise ValueError("UpConv3d: the input is not the stride-2 parent of the target coordinates")
        if self.compute_dtype is not None:
            children, pick = target.cset.children()
            out = _UpConvIm2colFn.apply(x.feats, self.weight, children, pick, self.compute_dtype)
            if self.bias is not None:
                out = out + self.bias.to(out.dtype)
            return SparseTensor(feats=out, cset=target.cset, stride=target.stride)
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
        # (biased variance) at a fraction of the general path's time (experiments/fidelity-log.md, "Cost").
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
