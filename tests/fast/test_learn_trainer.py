"""The one training loop (``assist3d.learn.trainer``): counters, hook order, rate schedule, stopping,
checkpoint cadence, weight averaging and the divergence guard, on a model small enough to check by hand."""

from __future__ import annotations

import math

import pytest

torch = pytest.importorskip("torch")

from assist3d.learn.trainer import CallbackHook, CheckpointHook, EMAHook, Hook, Trainer, update_ema  # noqa: E402


def _linear():
    torch.manual_seed(0)
    return torch.nn.Linear(2, 1, bias=False)


def _loss(model, batch):
    x, y = batch
    loss = ((model(x).squeeze(1) - y) ** 2).mean()
    return loss, {"loss": float(loss.detach()), "half": float(loss.detach()) / 2}


def _batches(n):
    g = torch.Generator().manual_seed(1)
    for _ in range(n):
        x = torch.randn(8, 2, generator=g)
        yield x, x @ torch.tensor([1.5, -2.0])


class _Order(Hook):
    def __init__(self, name, seen):
        self.name, self.seen = name, seen

    def before_fit(self, trainer):
        self.seen.append(("before", self.name, trainer.steps))

    def after_step(self, trainer, record):
        self.seen.append(("step", self.name, record["step"]))

    def after_fit(self, trainer):
        self.seen.append(("after", self.name, trainer.steps))


def test_fit_counts_steps_calls_hooks_in_order_and_stops_on_until_or_when_batches_end():
    model = _linear()
    seen: list = []
    t = Trainer(model, torch.optim.SGD(model.parameters(), lr=0.1), _loss,
                hooks=[_Order("a", seen), _Order("b", seen)])
    t.fit(_batches(10), until=lambda tr: tr.steps >= 3)
    assert t.steps == 3 and t.seconds > 0
    assert seen == [("before", "a", 0), ("before", "b", 0), ("step", "a", 1), ("step", "b", 1), ("step", "a", 2),
                    ("step", "b", 2), ("step", "a", 3), ("step", "b", 3), ("after", "a", 3), ("after", "b", 3)]
    t.fit(_batches(2))  # a second fit continues the counters and ends with its batches
    assert t.steps == 5
    assert math.isfinite(t.last_loss)


def test_the_loss_falls_and_records_carry_the_rate_each_step_used():
    model = _linear()
    rates = [0.2, 0.1, 0.05, 0.025]
    records: list = []
    t = Trainer(model, torch.optim.SGD(model.parameters(), lr=1.0), _loss, lr_at=lambda tr: rates[tr.steps],
                hooks=[CallbackHook(records.append, lambda tr: {"extra": tr.steps * 10})])
    t.fit(_batches(4))
    assert [r["lr"] for r in records] == rates
    assert [r["extra"] for r in records] == [10, 20, 30, 40]
    assert records[-1]["loss"] < records[0]["loss"] and records[0]["half"] == records[0]["loss"] / 2
    # a torch scheduler is stepped after each step: the record has the rate before it
    model2 = _linear()
    opt = torch.optim.SGD(model2.parameters(), lr=0.1)
    rec2: list = []
    t2 = Trainer(model2, opt, _loss, scheduler=torch.optim.lr_scheduler.StepLR(opt, 1, gamma=0.5),
                 hooks=[CallbackHook(rec2.append)])
    t2.fit(_batches(3))
    assert [r["lr"] for r in rec2] == pytest.approx([0.1, 0.05, 0.025])


def test_gradients_are_clipped_to_the_given_norm():
    model = _linear()
    before = model.weight.detach().clone()
    t = Trainer(model, torch.optim.SGD(model.parameters(), lr=1.0), lambda m, b: (m.weight.sum() * 1e6, {"loss": 0.0}),
                grad_clip=0.5)
    t.fit([None])
    assert float((model.weight.detach() - before).norm()) == pytest.approx(0.5, rel=1e-5)


def test_a_non_finite_loss_stops_the_run_when_guarded():
    model = _linear()
    nan = lambda m, b: (m.weight.sum() * float("nan"), {"loss": float("nan")})  # noqa: E731
    with pytest.raises(FloatingPointError, match="diverged at step 0"):
        Trainer(model, torch.optim.SGD(model.parameters(), lr=0.1), nan, check_finite=True).fit([None])
    t = Trainer(model, torch.optim.SGD(model.parameters(), lr=0.1), nan)  # unguarded: it is the caller's choice
    t.fit([None])
    assert t.steps == 1


def test_checkpoints_every_n_steps_and_at_the_end_but_not_after_an_error():
    model = _linear()
    saved: list = []
    hook = CheckpointHook(lambda tr: saved.append(tr.steps), every_steps=2)
    Trainer(model, torch.optim.SGD(model.parameters(), lr=0.1), _loss, hooks=[hook]).fit(_batches(5))
    assert saved == [2, 4, 5]

    def boom(m, b):
        raise RuntimeError("broken batch")

    saved.clear()
    with pytest.raises(RuntimeError):
        Trainer(model, torch.optim.SGD(model.parameters(), lr=0.1), boom, hooks=[hook]).fit(_batches(3))
    assert saved == []


def test_weight_averaging_follows_the_warm_up_formula():
    model = _linear()
    start = model.weight.detach().clone()
    ema = EMAHook(model, decay=0.9)
    t = Trainer(model, torch.optim.SGD(model.parameters(), lr=0.1), _loss, hooks=[ema])
    t.fit(_batches(1))
    d = min(0.9, 1 / 10)  # step 0
    assert torch.allclose(ema.ema.weight, d * start + (1 - d) * model.weight.detach())
    assert not ema.ema.weight.requires_grad
    a, b = _linear(), torch.nn.Linear(2, 1, bias=False)
    with torch.no_grad():
        b.weight.fill_(1.0)
    a0 = a.weight.detach().clone()
    update_ema(a, b, 0.9, 1000)
    assert torch.allclose(a.weight, 0.9 * a0 + 0.1)


def _square(k):
    return {"k": k, "sq": k * k}


def test_the_one_loader_gives_the_same_batches_with_workers_and_stops_where_told():
    from assist3d.core.errors import ConfigError
    from assist3d.learn.loader import StepLoader

    with StepLoader(_square, 3, 7) as here:
        a = list(here)
    with StepLoader(_square, 3, 7, workers=2, prefetch=1) as there:
        b = list(there)
    assert a == b == [{"k": k, "sq": k * k} for k in range(3, 7)]
    with StepLoader(_square, 5) as endless:  # no stop: the training loop decides
        assert [endless.next() for _ in range(3)] == [(5, _square(5)), (6, _square(6)), (7, _square(7))]
    with pytest.raises(RuntimeError, match="outside its 'with' block"):
        StepLoader(_square).next()
    with pytest.raises(ConfigError, match="loader workers 65"):
        StepLoader(_square, workers=65)


def test_transforms_compose_into_recipes_that_keep_rows_and_draw_in_order():
    import numpy as np

    from assist3d.learn.transforms import (Centre, ColorJitter, Compose, CropSquare, Mirror, Points, Rotate, Scale,
                                           Thin)

    g = np.random.default_rng(0)
    coord = g.random((400, 3)) * [8.0, 6.0, 3.0]
    color = g.random((400, 3)) * 255
    whole = Points.of(coord, color)
    recipe = Compose([CropSquare(3.0), Thin(0.5, 0.5, fallback=whole), Centre(xy_only=True), Mirror((0,)),
                      Rotate(0.0, 0.0, np.pi), Scale(0.1), ColorJitter(0.2)])
    a, b = recipe(whole, np.random.default_rng(5)), recipe(whole, np.random.default_rng(5))
    assert np.array_equal(a.coord, b.coord) and np.array_equal(a.rows, b.rows)  # a pure function of the stream
    assert 0 < len(a.rows) < 400 and np.array_equal(np.sort(a.rows), np.unique(a.rows))
    # rows point back at the input: the crop keeps points of one 3 m window (before the rigid moves)
    assert np.ptp(coord[a.rows, 0]) <= 3.0 + 1e-9 and np.ptp(coord[a.rows, 1]) <= 3.0 + 1e-9
    # a rotation about z keeps each point's distance to the vertical axis through the (xy-centred) mean
    r = Compose([Centre(xy_only=True), Rotate(0.0, 0.0, np.pi)])(whole, np.random.default_rng(1))
    c = whole.coord[:, :2] - whole.coord[:, :2].mean(0)
    assert np.allclose(np.hypot(*r.coord[:, :2].T), np.hypot(*c.T)) and np.allclose(r.coord[:, 2], whole.coord[:, 2])
    # a crop that leaves too few points falls back to the whole scene
    tiny = Compose([CropSquare(1e-6), Thin(1.0, 1.0, fallback=whole)])(whole, np.random.default_rng(2))
    assert len(tiny.rows) == 400
