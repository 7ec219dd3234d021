"""Sparse convolutions equal dense conv3d / conv_transpose3d at the active sites (values and gradients)."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")
import torch.nn.functional as F  # noqa: E402

from assist3d.learn.models import sparse as sp  # noqa: E402
from assist3d.learn.models import spconv_backend  # noqa: E402

BACKENDS = ["torch", pytest.param("spconv", marks=pytest.mark.skipif(not spconv_backend.available(),
                                                                     reason="spconv not installed"))]


@pytest.fixture(params=BACKENDS)
def backend(request):
    return request.param


DT = torch.float32


def _random_sites(gen: torch.Generator, batch: int, size: int, n: int) -> torch.Tensor:
    flat = torch.randperm(batch * size ** 3, generator=gen)[:n]
    b = flat // size ** 3
    r = flat % size ** 3
    return torch.stack([b, r // size ** 2, (r // size) % size, r % size], 1).to(torch.int32)


def _scatter(dense: torch.Tensor, c: torch.Tensor, feats: torch.Tensor) -> torch.Tensor:
    d = dense.permute(0, 2, 3, 4, 1).clone()
    d = d.index_put((c[:, 0], c[:, 1], c[:, 2], c[:, 3]), feats)
    return d.permute(0, 4, 1, 2, 3)


def _read(dense: torch.Tensor, c: torch.Tensor) -> torch.Tensor:
    c = c.long()
    return dense.permute(0, 2, 3, 4, 1)[c[:, 0], c[:, 1], c[:, 2], c[:, 3]]


def _has_backward(backend: str) -> bool:
    """spconv 2.3's CPU package runs forward only (its backward asks for a CUDA stream)."""
    return backend == "torch" or torch.cuda.is_available()


def _close(a, b):
    torch.testing.assert_close(a, b, rtol=1e-4, atol=1e-4)


@pytest.mark.parametrize("k", [1, 3, 5])
@pytest.mark.slow
def test_submanifold_equals_dense(k, backend):
    gen = torch.Generator().manual_seed(k)
    coords = _random_sites(gen, 2, 7, 150)
    feats = torch.randn(150, 4, generator=gen, dtype=DT, requires_grad=True)
    conv = sp.use_backend(sp.SubMConv3d(4, 5, kernel_size=k).to(DT), backend)
    out = conv(sp.sparse_tensor(coords, feats)).feats
    dense_w = conv.weight.detach().clone().reshape(k, k, k, 4, 5).permute(4, 3, 0, 1, 2).requires_grad_(True)
    feats2 = feats.detach().clone().requires_grad_(True)
    ref = _read(F.conv3d(_scatter(torch.zeros(2, 4, 7, 7, 7, dtype=DT), coords.long(), feats2),
                         dense_w, padding=k // 2), coords)
    _close(out, ref)
    if not _has_backward(backend):
        return
    g = torch.randn(out.shape, generator=gen, dtype=DT)
    (out * g).sum().backward()
    (ref * g).sum().backward()
    _close(feats.grad, feats2.grad)
    _close(conv.weight.grad.reshape(k, k, k, 4, 5).permute(4, 3, 0, 1, 2), dense_w.grad)


def test_down_and_up_equal_dense(backend):
    gen = torch.Generator().manual_seed(7)
    coords = _random_sites(gen, 2, 8, 200)
    feats = torch.randn(200, 3, generator=gen, dtype=DT, requires_grad=True)
    x = sp.sparse_tensor(coords, feats)
    down = sp.DownConv3d(3, 4).to(DT)
    y = down(x)
    dense_w = down.weight.detach().clone().reshape(2, 2, 2, 3, 4).permute(4, 3, 0, 1, 2).requires_grad_(True)
    feats2 = feats.detach().clone().requires_grad_(True)
    dense_in = _scatter(torch.zeros(2, 3, 8, 8, 8, dtype=DT), coords.long(), feats2)
    dense_y = F.conv3d(dense_in, dense_w, stride=2)
    ref = _read(dense_y, y.coords)
    _close(y.feats, ref)
    # the coarse sites are exactly the parents of the active sites
    parents = {tuple(r) for r in torch.cat([coords[:, :1], coords[:, 1:] // 2], 1).tolist()}
    assert {tuple(r) for r in y.coords.tolist()} == parents
    up = sp.use_backend(sp.UpConv3d(4, 2).to(DT), backend)
    z = up(y, x)
    up_w = up.weight.detach().clone().reshape(2, 2, 2, 4, 2).permute(3, 4, 0, 1, 2).requires_grad_(True)
    ref_z = _read(F.conv_transpose3d(dense_y, up_w, stride=2), coords)
    _close(z.feats, ref_z)
    if not _has_backward(backend):
        return
    g = torch.randn(z.feats.shape, generator=gen, dtype=DT)
    (z.feats * g).sum().backward()
    (ref_z * g).sum().backward()
    _close(feats.grad, feats2.grad)
    _close(down.weight.grad.reshape(2, 2, 2, 3, 4).permute(4, 3, 0, 1, 2), dense_w.grad)
    _close(up.weight.grad.reshape(2, 2, 2, 4, 2).permute(3, 4, 0, 1, 2), up_w.grad)


@pytest.mark.skipif(not spconv_backend.available(), reason="spconv not installed")
def test_spconv_cpu_calls_run_single_threaded(monkeypatch):
    """spconv's CPU kernels race on PyTorch's thread pool (wrong rows now and then with 2 threads):
    every CPU call must run with one intra-op thread, and the caller's setting comes back."""
    seen = []
    m = spconv_backend._module("subm", 4, 5, 3)
    real = m._conv_forward

    def spy(*a, **k):
        seen.append(torch.get_num_threads())
        return real(*a, **k)

    monkeypatch.setattr(m, "_conv_forward", spy)
    before = torch.get_num_threads()
    torch.set_num_threads(2)
    try:
        gen = torch.Generator().manual_seed(0)
        coords = _random_sites(gen, 1, 6, 40)
        spconv_backend.subm_conv(coords, torch.randn(40, 4, generator=gen), torch.randn(27, 4, 5, generator=gen), 3)
        assert seen == [1] and torch.get_num_threads() == 2
    finally:
        torch.set_num_threads(before)


def test_the_kernel_choice_belongs_to_each_model():
    a = torch.nn.ModuleList([sp.SubMConv3d(2, 2), sp.UpConv3d(2, 2), sp.DownConv3d(2, 2)])
    b = torch.nn.ModuleList([sp.SubMConv3d(2, 2)])
    assert sp.use_backend(a, "torch") is a
    assert [m.backend for m in a if hasattr(m, "backend")] == ["torch", "torch"] and b[0].backend == "torch"
    with pytest.raises(ValueError, match="unknown sparse backend"):
        sp.use_backend(a, "cuda")
    if not spconv_backend.available():
        with pytest.raises(Exception, match="spconv"):
            sp.use_backend(b, "spconv")
        assert b[0].backend == "torch"  # a refused switch changes nothing


def _layers_with_grads(make, x_feats, run, compute_dtype):
    """Output and gradients (input, weight) of a freshly made layer run with ``compute_dtype``."""
    torch.manual_seed(0)
    layer = make()
    for m in layer.modules():
        if hasattr(m, "compute_dtype"):
            m.compute_dtype = compute_dtype
    f = x_feats.detach().clone().requires_grad_(True)
    out = run(layer, f)
    g = torch.linspace(-1, 1, out.numel(), dtype=out.dtype).view_as(out)
    (out * g).sum().backward()
    return out.detach(), f.grad, layer.weight.grad


@pytest.fixture
def small_blocks(monkeypatch):
    """im2col blocks of 64 rows, buckets 16 / 64: several blocks and a padded last one in tiny tests."""
    monkeypatch.setattr(sp, "IM2COL_ROWS", 64)
    monkeypatch.setattr(sp, "_ROW_BUCKETS", (16, 64))


@pytest.mark.parametrize("k", [1, 3, 5])
@pytest.mark.slow
def test_im2col_convolutions_equal_the_per_offset_path(k, small_blocks):
    """The im2col path (the bfloat16 training path's arithmetic, run here in float32 and float64)
    gives the per-offset path's outputs and gradients for every operator, over several padded blocks."""
    gen = torch.Generator().manual_seed(10 + k)
    coords = _random_sites(gen, 2, 9, 300)
    for dt, close in ((torch.float32, _close),
                      (torch.float64, lambda a, b: torch.testing.assert_close(a, b, rtol=1e-10, atol=1e-10))):
        feats = torch.randn(300, 4, generator=gen, dtype=dt)
        x = sp.sparse_tensor(coords, feats)
        coarse = sp.DownConv3d(4, 4).to(dt)(x)
        cases = [
            (lambda: sp.SubMConv3d(4, 5, kernel_size=k).to(dt), feats, lambda m, f: m(x.replace(f)).feats),
            (lambda: sp.DownConv3d(4, 6).to(dt), feats, lambda m, f: m(x.replace(f)).feats),
            (lambda: sp.UpConv3d(4, 3).to(dt), coarse.feats, lambda m, f: m(coarse.replace(f), x).feats),
        ]
        for make, inp, run in cases:
            ref = _layers_with_grads(make, inp, run, None)
            got = _layers_with_grads(make, inp, run, dt)
            for a, b in zip(got, ref):
                close(a, b)


@pytest.mark.slow
def test_bfloat16_precision_stays_close_and_float32_at_the_boundary():
    gen = torch.Generator().manual_seed(3)
    coords = _random_sites(gen, 1, 16, 900)
    feats = torch.randn(900, 16, generator=gen)
    make = lambda: sp.SubMConv3d(16, 16, 3)  # noqa: E731
    run = lambda m, f: m(sp.sparse_tensor(coords, f)).feats  # noqa: E731
    ref = _layers_with_grads(make, feats, run, None)
    got = _layers_with_grads(make, feats, run, torch.bfloat16)
    for a, b in zip(got, ref):
        assert a.dtype == torch.float32
        assert float((a - b).norm() / b.norm()) < 2e-2  # bfloat16 inputs: ~3 significant digits
    # use_precision reaches every sparse convolution and only them
    net = torch.nn.Sequential(sp.SubMConv3d(2, 2, 3), sp.DownConv3d(2, 2), sp.SparseLinear(2, 2))
    sp.use_precision(net, "bfloat16")
    assert net[0].compute_dtype == net[1].compute_dtype == torch.bfloat16
    assert not hasattr(net[2], "compute_dtype")
    sp.use_precision(net, "float32")
    assert net[0].compute_dtype is None
    with pytest.raises(ValueError, match="precision"):
        sp.use_precision(net, "float16")


def test_neighbour_table_dense_grid_equals_sorted_search(monkeypatch):
    gen = torch.Generator().manual_seed(5)
    coords = _random_sites(gen, 3, 10, 500)
    coords[:, 1:] -= 4  # negative coordinates too
    cset = sp.CoordSet.build(coords)
    dense = sp._neighbour_table(cset, 3)
    monkeypatch.setattr(sp, "DENSE_GRID_CELLS", 0)
    searched = sp._neighbour_table(sp.CoordSet.build(coords), 3)
    assert torch.equal(dense, searched)
    # the centre offset is the site itself; a neighbour in another scene is never returned
    assert torch.equal(dense[:, 13], torch.arange(500))
    hit = dense < 500
    rows = torch.arange(500)[:, None].expand_as(dense)
    assert torch.equal(coords[dense[hit], 0], coords[rows[hit], 0])


def test_auto_precision_follows_the_cpu(monkeypatch):
    assert sp.resolve_precision("float32") == "float32"
    assert sp.resolve_precision("auto", "cpu") == ("bfloat16" if sp.native_bfloat16() else "float32")
    monkeypatch.setattr(sp, "native_bfloat16", lambda device="cpu": False)
    assert sp.resolve_precision("auto") == "float32"
    with pytest.raises(ValueError):
        sp.resolve_precision("fp8")


def test_kernel_maps_from_the_dense_table_equal_the_searched_maps(monkeypatch):
    gen = torch.Generator().manual_seed(11)
    coords = _random_sites(gen, 2, 9, 400)
    coords[:, 1:] -= 3
    dense = sp.CoordSet.build(coords).submanifold_map(3)
    monkeypatch.setattr(sp, "DENSE_GRID_CELLS", 0)  # forces the sorted-key search
    searched = sp.CoordSet.build(coords).submanifold_map(3)
    assert len(dense) == len(searched) == 27
    assert dense[13] is None and searched[13] is None
    for a, b in zip(dense, searched):
        if a is not None:
            assert torch.equal(a[0], b[0]) and torch.equal(a[1], b[1])
    # every pair really is a neighbour at that offset, in the same scene
    offs = sp.kernel_offsets(3)
    for o, m in enumerate(dense):
        if m is not None and len(m[1]):
            src, dst = coords[m[0]].long(), coords[m[1]].long()
            assert torch.equal(src[:, 0], dst[:, 0])
            assert torch.equal(src[:, 1:] - dst[:, 1:], offs[o].expand(len(src), 3))
