"""Matcher, losses, one training step, checkpoint round trip, predict output, DBSCAN, voxelisation."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from assist3d.learn.engine.config import LossConfig, parse_data_arg, parse_train_config  # noqa: E402
from assist3d.learn.engine.losses import layer_loss, scene_loss  # noqa: E402
from assist3d.learn.engine.matcher import hungarian_match, match_cost  # noqa: E402
from assist3d.learn.engine.predict import dbscan_labels, predict_scene  # noqa: E402
from assist3d.learn.engine.toy import make_toy_scene  # noqa: E402
from assist3d.learn.engine.train import MemorySource, Trainer, load_checkpoint, save_checkpoint, train  # noqa: E402
from assist3d.learn.engine.voxelize import majority_label, voxelize  # noqa: E402
from assist3d.learn.models.decoder import LayerPrediction  # noqa: E402

TINY = {
    "threads": 1,
    "model": {"stem_channels": 8, "stem_kernel": 3, "enc_channels": [8, 16, 16, 24], "enc_blocks": [1, 1, 1, 1],
              "dec_channels": [24, 16, 16, 16], "dec_blocks": [1, 1, 1, 1], "hidden": 32, "heads": 4, "ffn": 64,
              "num_passes": 1, "num_queries": 12, "num_queries_eval": 12},
    "data": {"voxel_size": 0.1},
    "augment": {"enabled": False},
    "optim": {"lr": 0.003, "batch_size": 2, "epochs": 2, "pct_start": 0.5},
    "predict": {"top_k": 12},
}


def _scenes(n: int = 2) -> list:
    return [make_toy_scene(f"s{i}", rng=np.random.default_rng(i), num_objects=3, room_m=3.0, density_per_m2=150)
            for i in range(n)]


@pytest.mark.parametrize("seed", range(6))
def test_matcher_is_optimal_against_brute_force(seed):
    gen = torch.Generator().manual_seed(seed)
    q, g, n = 5, 3 + seed % 3, 40
    obj = torch.randn(q, generator=gen)
    masks = torch.randn(n, q, generator=gen) * 3
    targets = (torch.rand(n, g, generator=gen) > 0.6).float()
    rows, cols = hungarian_match(obj, masks, targets)
    cost = match_cost(obj, masks, targets).numpy()
    got = cost[rows, cols].sum()
    best = min(sum(cost[p[j], j] for j in range(g)) for p in itertools.permutations(range(q), g))
    assert len(rows) == g and len(set(rows.tolist())) == g
    assert got == pytest.approx(best, abs=1e-5)


def test_matcher_recovers_a_permutation():
    targets = torch.zeros(30, 3)
    targets[:10, 0] = targets[10:20, 1] = targets[20:, 2] = 1
    perm = [2, 0, 1]
    masks = torch.full((30, 4), -20.0)
    for qi, ti in enumerate(perm):
        masks[:, qi] = torch.where(targets[:, ti] > 0, 20.0, -20.0)
    rows, cols = hungarian_match(torch.tensor([5.0, 5.0, 5.0, -5.0]), masks, targets)
    assert dict(zip(cols.tolist(), rows.tolist())) == {2: 0, 0: 1, 1: 2}


def test_losses_vanish_on_perfect_predictions():
    targets = torch.zeros(50, 2)
    targets[:20, 0] = 1
    targets[30:, 1] = 1
    masks = torch.full((50, 4), -60.0)
    masks[:, 1] = torch.where(targets[:, 0] > 0, 60.0, -60.0)
    masks[:, 3] = torch.where(targets[:, 1] > 0, 60.0, -60.0)
    obj = torch.tensor([-60.0, 60.0, -60.0, 60.0])
    parts = layer_loss(LayerPrediction(obj, masks), targets, LossConfig())
    assert float(parts.total) < 1e-6
    # a wrong objectness on one query makes it positive
    bad = layer_loss(LayerPrediction(torch.tensor([60.0, 60.0, -60.0, 60.0]), masks), targets, LossConfig())
    assert float(bad.objectness) > 1.0
    # auxiliary layers add their own matched losses
    imperfect = LayerPrediction(obj, torch.zeros_like(masks))
    both = scene_loss([imperfect, LayerPrediction(obj, masks)], targets, LossConfig())
    only = scene_loss([imperfect, LayerPrediction(obj, masks)], targets, LossConfig(aux=False))
    assert float(only.total) < 1e-6 < float(both.total)


def test_voxelize_majority_and_inverse():
    coord = np.array([[0.01, 0.01, 0.01], [0.02, 0.03, 0.01], [0.04, 0.01, 0.02], [0.5, 0.5, 0.5]], np.float32)
    color = np.array([[255, 0, 0], [0, 0, 255], [0, 0, 255], [10, 10, 10]], np.uint8)
    inst = np.array([3, 7, 7, -1], np.int32)
    vox = voxelize(coord, color, inst, 0.05)
    assert len(vox.coords) == 2
    assert vox.inverse[0] == vox.inverse[1] == vox.inverse[2] != vox.inverse[3]
    assert vox.instance[vox.inverse[0]] == 7 and vox.instance[vox.inverse[3]] == -1
    assert (majority_label(np.array([0, 0, 1, 1]), np.array([5, 2, 4, 4]), 3) == [2, 4, -1]).all()


def test_majority_label_matches_a_per_group_vote_on_random_labels():
    rng = np.random.default_rng(3)
    for n, groups, labels in ((500, 40, 5), (2000, 300, 60), (50, 10, 2)):
        group = rng.integers(0, groups, n)
        label = rng.integers(-1, labels, n)  # -1: unlabelled points vote too
        if labels > 50:
            label[::7] = 2 ** 60  # a label range too wide for one int64 key: the row-wise path
        got = majority_label(group, label, groups + 3)
        for g in range(groups + 3):
            vals, cnt = np.unique(label[group == g], return_counts=True)
            want = vals[cnt == cnt.max()].min() if len(vals) else -1
            assert got[g] == want
    assert (majority_label(np.zeros(0, np.int64), np.zeros(0, np.int64), 2) == [-1, -1]).all()


@pytest.mark.slow
def test_one_training_step_lowers_the_loss():
    cfg = parse_train_config(TINY)
    trainer = Trainer(cfg, MemorySource(_scenes()), steps_total=50)
    before, _ = trainer.batch_loss([0, 1], rng=np.random.default_rng(0), augment=False)
    trainer.model.train()
    for _ in range(3):
        trainer.step([0, 1], rng=np.random.default_rng(0))
    torch.manual_seed(0)
    after, _ = trainer.batch_loss([0, 1], rng=np.random.default_rng(0), augment=False)
    assert float(after.detach()) < float(before.detach())


def test_synthetic_scenes_are_weighted_by_alpha():
    cfg = parse_train_config({**TINY, "data": {"voxel_size": 0.1, "synthetic_alpha": 0.25}})
    scenes = _scenes(1)
    losses = []
    for synthetic in (False, True):
        trainer = Trainer(cfg, MemorySource(scenes, [synthetic]), steps_total=5)
        trainer.model.eval()
        torch.manual_seed(0)
        loss, _ = trainer.batch_loss([0], rng=np.random.default_rng(0), augment=False)
        losses.append(float(loss.detach()))
    assert losses[1] == pytest.approx(0.25 * losses[0], rel=1e-5)


def test_data_arg_kinds():
    assert parse_data_arg("assist3d:/x").resolved_kind() == "synthetic"
    assert parse_data_arg("scannet:/x").resolved_kind() == "real"
    assert parse_data_arg("real=assist3d:/x").resolved_kind() == "real"
    assert parse_data_arg("synthetic=pointcept:/x").resolved_kind() == "synthetic"


@pytest.mark.slow
def test_train_checkpoint_resume_round_trip(tmp_path):
    cfg = parse_train_config({**TINY, "optim": {**TINY["optim"], "epochs": 2}})
    src = MemorySource(_scenes())
    res = train(cfg, tmp_path, source=src)
    state = load_checkpoint(tmp_path / "last.pt")
    assert state["epoch"] == 2 and state["step"] == res.steps == 2
    assert (tmp_path / "epoch_0002.pt").is_file() and (tmp_path / "config.yaml").is_file()
    rows = (tmp_path / "metrics.csv").read_text().strip().splitlines()
    assert rows[0].startswith("epoch,step") and len(rows) == 3
    # resuming a finished run keeps its state; extending the schedule continues from the saved step
    cfg3 = parse_train_config({**TINY, "optim": {**TINY["optim"], "epochs": 3}})
    trainer = Trainer(cfg3, src, steps_total=3)
    trainer.restore(state)
    for k, v in state["model"].items():
        torch.testing.assert_close(trainer.state()["model"][k], v)
    assert trainer.scheduler.state_dict()["last_epoch"] == state["scheduler"]["last_epoch"]
    save_checkpoint(tmp_path / "copy.pt", trainer.model, trainer.optimizer, trainer.scheduler, 2, 2, cfg)
    again = load_checkpoint(tmp_path / "copy.pt")
    for k, v in state["model"].items():
        torch.testing.assert_close(again["model"][k], v)


@pytest.mark.slow
def test_resume_continues_training(tmp_path):
    cfg1 = parse_train_config({**TINY, "optim": {**TINY["optim"], "epochs": 1}})
    src = MemorySource(_scenes())
    train(cfg1, tmp_path, source=src)
    cfg2 = parse_train_config({**TINY, "optim": {**TINY["optim"], "epochs": 6}})
    res = train(cfg2, tmp_path, resume=True, source=src)
    state = load_checkpoint(tmp_path / "last.pt")
    assert res.steps == 6 and state["epoch"] == 6 and state["scheduler"]["total_steps"] == 6
    assert len((tmp_path / "metrics.csv").read_text().strip().splitlines()) == 7


def test_predict_scene_shapes_and_scores():
    cfg = parse_train_config(TINY)
    trainer = Trainer(cfg, MemorySource(_scenes(1)), steps_total=5)
    sample = _scenes(1)[0]
    pred = predict_scene(trainer.model, sample, cfg.data.voxel_size, cfg.predict)
    m = len(pred.scores)
    assert pred.masks.dtype == np.bool_ and pred.masks.shape == (m, len(sample))
    assert pred.scores.dtype == np.float32 and 0 < m <= cfg.predict.top_k
    assert (np.diff(pred.scores) <= 0).all() and ((pred.scores >= 0) & (pred.scores <= 1)).all()
    assert pred.masks.any(1).all()
    # the same voxel -> the same answer for every point in it
    vox = voxelize(sample.coord, sample.color, None, cfg.data.voxel_size)
    first = np.unique(vox.inverse, return_index=True)[1]
    assert (pred.masks == pred.masks[:, first][:, vox.inverse]).all()


def test_dbscan_splits_far_clusters():
    rng = np.random.default_rng(0)
    a = rng.normal(0, 0.05, (30, 3))
    b = rng.normal(5, 0.05, (20, 3))
    lab = dbscan_labels(np.concatenate([a, b, [[20, 20, 20]]]), eps=0.5, min_points=3)
    assert len(set(lab[:30])) == 1 and len(set(lab[30:50])) == 1 and lab[0] != lab[30] and lab[-1] == -1


def test_model_bench_reports_times(tmp_path):
    from assist3d.learn.engine.bench import run_model_bench

    res = run_model_bench(parse_train_config(TINY), points=3000, repeats=1)
    assert res.points == 3000 and 0 < res.voxels <= 3000
    assert res.forward_s > 0 and res.forward_backward_s > 0 and res.parameters > 0


def test_import_assist3d_does_not_import_torch():
    import subprocess
    import sys

    code = "import sys, assist3d, assist3d.cli, assist3d.learn.engine, assist3d.learn.models; print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_train_cli_requires_data(tmp_path):
    from typer.testing import CliRunner

    from assist3d.cli import app

    cfg = tmp_path / "c.yaml"
    cfg.write_text("optim: {epochs: 1}\n")
    res = CliRunner().invoke(app, ["train", "--config", str(cfg), "--out", str(tmp_path / "o")])
    assert res.exit_code != 0 and "no training data" in str(res.exception)


@pytest.mark.slow
def test_predict_cli_writes_evaluation_format(tmp_path):
    from typer.testing import CliRunner

    from assist3d.cli import app
    from assist3d.learn.engine.toy import write_pointcept_scene

    scenes = _scenes(2)
    for s in scenes:
        write_pointcept_scene(tmp_path / "data" / s.scene_id, s)
    cfg = parse_train_config({**TINY, "optim": {**TINY["optim"], "epochs": 1}})
    train(cfg, tmp_path / "run", source=MemorySource(scenes))
    res = CliRunner().invoke(app, ["predict", "--checkpoint", str(tmp_path / "run" / "last.pt"), "--data",
                                   f"pointcept:{tmp_path / 'data'}", "--out", str(tmp_path / "pred"),
                                   "--top-k", "5", "--device", "cpu"])
    assert res.exit_code == 0, res.output
    for s in scenes:
        with np.load(tmp_path / "pred" / f"{s.scene_id}.npz") as z:
            assert z["masks"].dtype == np.bool_ and z["masks"].shape[1] == len(s)
            assert z["scores"].dtype == np.float32 and len(z["scores"]) == len(z["masks"]) <= 5


def test_mixed_precision_forward_backward():
    """bf16 autocast (the CUDA AMP path, exercised here on the CPU) runs and keeps float32 gradients."""
    from assist3d.learn.engine.train import build_model
    from assist3d.learn.engine.voxelize import collate, instance_masks

    cfg = parse_train_config(TINY)
    torch.manual_seed(0)
    model = build_model(cfg.model)
    vox = voxelize(_scenes(1)[0].coord, _scenes(1)[0].color, _scenes(1)[0].instance, 0.1)
    coords, feats = collate([vox])
    targets = torch.from_numpy(np.ascontiguousarray(instance_masks(vox.instance)[0].T)).float()
    with torch.autocast("cpu", dtype=torch.bfloat16):
        preds = model(coords, feats, 1)
    loss = scene_loss(preds[0], targets, cfg.loss).total
    loss.backward()
    assert torch.isfinite(loss)
    grads = [p.grad for p in model.parameters() if p.grad is not None]
    assert grads and all(g.dtype == torch.float32 and torch.isfinite(g).all() for g in grads)


def test_presets_load_and_paper_defaults():
    from pathlib import Path

    from assist3d.learn.engine.config import TrainConfig, load_train_config

    configs = Path(__file__).resolve().parents[2] / "configs"
    paper = load_train_config(configs / "paper.yaml")
    assert paper.model == TrainConfig().model and paper.loss == TrainConfig().loss
    assert paper.data.voxel_size == 0.02 and paper.data.synthetic_alpha == 0.5
    assert [d.resolved_kind() for d in paper.data.train] == ["real", "synthetic"]
    small = load_train_config(configs / "small-cpu.yaml")
    assert small.model.hidden < paper.model.hidden and small.threads == 1


class _Recorder:
    """A training logger that keeps every row it is given."""

    def __init__(self):
        self.rows, self.closed = [], False

    def log(self, rows):
        self.rows += [dict(r) for r in rows]

    def close(self):
        self.closed = True


def test_custom_loggers_get_every_step_and_replace_the_default_files(tmp_path):
    rec = _Recorder()
    cfg = parse_train_config({**TINY, "optim": {**TINY["optim"], "epochs": 2}})
    res = train(cfg, tmp_path, source=MemorySource(_scenes()), loggers=[rec])
    assert [r["step"] for r in rec.rows] == [1, 2] and [r["epoch"] for r in rec.rows] == [1, 2] and rec.closed
    assert all(np.isfinite(r["loss"]) for r in rec.rows) and rec.rows[-1]["loss"] == res.last_loss
    assert not (tmp_path / "metrics.csv").exists()


def test_csv_log_truncates_by_its_step_column(tmp_path):
    from assist3d.learn.engine.loggers import CsvLog

    log = CsvLog(tmp_path / "m.csv", ("epoch", "step", "loss"))
    log.log([{"epoch": 1, "step": s, "loss": 0.5} for s in (1, 2, 3)])
    log.log([{"epoch": 2, "step": 4, "loss": 0.25}])
    log.truncate(2)
    assert (tmp_path / "m.csv").read_text().splitlines() == ["epoch,step,loss", "1,1,0.5", "1,2,0.5"]
    log.log([{"epoch": 1, "step": 3, "loss": 0.125}])  # no second header
    assert (tmp_path / "m.csv").read_text().splitlines()[1:] == ["1,1,0.5", "1,2,0.5", "1,3,0.125"]


def test_loader_workers_prepare_the_same_batches_in_order():
    from assist3d.learn.engine.loader import epoch_batches

    cfg = parse_train_config({**TINY, "augment": {"enabled": True}, "data": {"voxel_size": 0.1, "max_points": 2000}})
    src = MemorySource(_scenes(3))
    order = [2, 0, 1]
    here = list(epoch_batches(src, cfg, order, epoch=1, rank=0, workers=0))
    there = list(epoch_batches(src, cfg, order, epoch=1, rank=0, workers=2))
    assert [b.indices for b in here] == [b.indices for b in there] == [[2, 0], [1]]
    for a, b in zip(here, there):
        for (va, ma), (vb, mb) in zip(a.scenes, b.scenes):
            assert np.array_equal(va.coords, vb.coords) and np.array_equal(va.feats, vb.feats)
            assert np.array_equal(ma, mb)
    other_epoch = list(epoch_batches(src, cfg, order, epoch=2, rank=0, workers=0))
    assert not np.array_equal(other_epoch[0].scenes[0][0].coords, here[0].scenes[0][0].coords)  # fresh draws


@pytest.mark.slow
def test_training_with_loader_workers_equals_training_without(tmp_path):
    # TINY trains with threads: 1 (multi-threaded CPU reductions are not bit-reproducible)
    results = []
    for workers in (0, 1):
        cfg = parse_train_config({**TINY, "augment": {"enabled": True}, "data": {"voxel_size": 0.1, "workers": workers}})
        res = train(cfg, tmp_path / f"w{workers}", source=MemorySource(_scenes()))
        results.append((res.last_loss, load_checkpoint(tmp_path / f"w{workers}" / "last.pt")["model"]))
    assert results[0][0] == results[1][0]
    for k, v in results[0][1].items():
        assert torch.equal(v, results[1][1][k]), k
