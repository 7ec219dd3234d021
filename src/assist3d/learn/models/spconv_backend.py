"""Optional ``spconv`` 2.x backend for the submanifold and transposed convolutions of
:mod:`assist3d.learn.models.sparse` (the strided down-convolution always runs in pure PyTorch).

The weights stay the pure-PyTorch modules' parameters (``(k**3, C_in, C_out)``), so one checkpoint
runs on either backend; each call reshapes them to spconv's ``(C_out, kx, ky, kz, C_in)`` layout and
runs spconv's implicit-GEMM kernels through the module's ``_conv_forward``. Outputs are reordered to
the pure-PyTorch coordinate order, so the two backends are interchangeable layer by layer. The
transposed convolution has no cheap "onto these coordinates" form in spconv without sharing its
index dictionary, so it generates all eight children and the caller keeps the target ones.

Enable with ``use_backend(model, "spconv")`` (``model.backend: spconv`` in a training config).

On CPU, spconv 2.3's kernels run on PyTorch's intra-op thread pool and, with more than one thread,
now and then return wrong rows (measured: 1 of 30 identical submanifold calls differed, by up to
0.13, with 2 threads; 0 of 30 with 1): CPU calls therefore run with one thread.
"""

from __future__ import annotations

from contextlib import contextmanager

import torch

from ...core.errors import ConfigError


def _spconv():
    try:
        import spconv.pytorch as spc
    except ImportError as e:
        raise ConfigError(f"backend 'spconv' asked for but spconv is not installed ({e}); "
                          "pip install 'assist3d[spconv]' (CPU) or spconv-cu<CUDA version> (CUDA), or use backend torch") from None
    return spc


def available() -> bool:
    try:
        import spconv.pytorch  # noqa: F401
    except ImportError:
        return False
    return True


_MODULES: dict[tuple, object] = {}


def _module(kind: str, cin: int, cout: int, k: int):
    key = (kind, cin, cout, k)
    if key not in _MODULES:
        spc = _spconv()
        if kind == "subm":
            m = spc.SubMConv3d(cin, cout, k, bias=False)
        elif kind == "down":
            m = spc.SparseConv3d(cin, cout, 2, stride=2, bias=False)
        else:
            m = spc.SparseConvTranspose3d(cin, cout, 2, stride=2, bias=False)
        _MODULES[key] = m
    return _MODULES[key]


def _to_spconv(coords: torch.Tensor, feats: torch.Tensor, pad: int = 2):
    spc = _spconv()
    c = coords.to(torch.int32).contiguous()
    if len(c) and int(c[:, 1:].min()) < 0:
        raise ValueError("the spconv backend needs non-negative voxel coordinates")
    shape = (c[:, 1:].max(0).values + pad).tolist() if len(c) else [1, 1, 1]
    batch = int(c[:, 0].max()) + 1 if len(c) else 1
    return spc.SparseConvTensor(feats.contiguous(), c, shape, batch)


@contextmanager
def _safe_threads(t: torch.Tensor):
    """One intra-op thread around a CPU spconv call (see the module docstring)."""
    if t.device.type != "cpu":
        yield
        return
    n = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(n)


def _weight(w: torch.Tensor, k: int) -> torch.Tensor:
    return w.reshape(k, k, k, w.shape[1], w.shape[2]).permute(4, 0, 1, 2, 3).contiguous()


def subm_conv(coords: torch.Tensor, feats: torch.Tensor, weight: torch.Tensor, k: int) -> torch.Tensor:
    """Submanifold conv; ``weight`` (k**3, C_in, C_out); output rows in input order."""
    if k == 1:  # spconv itself runs a 1x1x1 conv as one matmul
        return feats @ weight[0]
    m = _module("subm", weight.shape[1], weight.shape[2], k)
    x = _to_spconv(coords, feats, pad=k)
    with _safe_threads(feats):
        y = m._conv_forward(m.training, x, _weight(weight, k), None)
    return y.features


def up_conv(coords: torch.Tensor, feats: torch.Tensor, weight: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Transposed kernel-2 stride-2 conv: its output sites ``(M, 4)`` and features ``(M, C)``
    (the caller reads them at the sites it needs)."""
    m = _module("up", weight.shape[1], weight.shape[2], 2)
    x = _to_spconv(coords, feats)
    with _safe_threads(feats):
        y = m._conv_forward(m.training, x, _weight(weight, 2), None)
    return y.indices, y.features
