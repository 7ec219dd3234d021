"""The one checkpoint format (``assist3d.learn.checkpoint``): both models write it, each reader refuses the
other model's file by name, and Mask3D-style files of the format before it still read."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")

from assist3d.core.errors import DataError  # noqa: E402
from assist3d.learn.checkpoint import Checkpoint, read_checkpoint, write_checkpoint  # noqa: E402


def _weights():
    g = torch.Generator().manual_seed(0)
    return {"w": torch.randn(40, 40, generator=g), "b": torch.randn(40, generator=g), "n": torch.tensor(3)}


def test_round_trip_keeps_every_part_and_names_the_model(tmp_path):
    ck = Checkpoint(model="mask3d", config={"a": 1}, state_dict=_weights(), meta={"m": "x"},
                    optimizer={"state": {}, "param_groups": [{"lr": 0.1, "params": [0]}]}, progress={"epoch": 2, "step": 7},
                    states={"scheduler": {"last_epoch": 7}})
    path = write_checkpoint(tmp_path / "c.pt", ck)
    raw = torch.load(path, weights_only=True)
    assert raw["format"] == "assist3d-mask3d" and raw["version"] == 1
    back = read_checkpoint(path)
    assert back.model == "mask3d" and back.config == {"a": 1} and back.meta == {"m": "x"}
    assert back.progress == {"epoch": 2, "step": 7} and back.states == {"scheduler": {"last_epoch": 7}}
    assert back.optimizer["param_groups"][0]["lr"] == 0.1
    assert all(torch.equal(back.state_dict[k], v) for k, v in _weights().items())
    with pytest.raises(DataError, match="not an assist3d segmenter checkpoint .*'assist3d-segmenter'"):
        read_checkpoint(path, model="segmenter")
    # int8: the big matrix coded, the rest half precision, decoded on read
    small = read_checkpoint(write_checkpoint(tmp_path / "q.pt", ck, precision="int8"))
    assert small.version == 2 and small.state_dict["w"].dtype == torch.float32
    assert (small.state_dict["w"] - _weights()["w"]).abs().max() < 0.05


def test_both_trainers_write_the_format_and_the_mask3d_file_of_before_still_reads(tmp_path):
    from assist3d.learn.engine.train import load_checkpoint

    legacy = {"model": _weights(), "optimizer": None, "scheduler": {"last_epoch": 4}, "scaler": None, "epoch": 1,
              "step": 4, "config": {"seed": 3}}
    torch.save(legacy, tmp_path / "old.pt")
    state = load_checkpoint(tmp_path / "old.pt")
    assert state["epoch"] == 1 and state["step"] == 4 and state["config"] == {"seed": 3}
    assert state["scheduler"] == {"last_epoch": 4} and state["scaler"] is None
    assert torch.equal(state["model"]["w"], legacy["model"]["w"])
    seg = write_checkpoint(tmp_path / "seg.pt", Checkpoint(model="segmenter", config={}, state_dict=_weights()))
    with pytest.raises(DataError, match="not an assist3d mask3d checkpoint"):
        load_checkpoint(seg)
    torch.save({"format": "assist3d-mask3d", "version": 9, "state_dict": {}}, tmp_path / "future.pt")
    with pytest.raises(DataError, match="version 9"):
        read_checkpoint(tmp_path / "future.pt")
    with pytest.raises(DataError, match="checkpoint not found"):
        read_checkpoint(tmp_path / "missing.pt")


@pytest.mark.slow  # trains a Mask3D-style model for an epoch
def test_one_predictor_runs_either_model_from_its_checkpoint(tmp_path):
    """``Predictor.load`` reads the model a checkpoint names: a Mask3D-style file gives the model's own
    instances, the same masks as the model's predict_scene, and refuses segmenter-only steps by name."""
    import sys
    from pathlib import Path

    import numpy as np

    sys.path.insert(0, str(Path(__file__).parent))
    import test_learn_engine as engine_tests
    from assist3d.learn.engine.config import parse_train_config
    from assist3d.learn.engine.predict import load_model, predict_scene
    from assist3d.learn.engine.train import MemorySource, train
    from assist3d.learn.segmenter.predictor import Predictor

    cfg = parse_train_config({**engine_tests.TINY, "optim": {**engine_tests.TINY.get("optim", {}), "epochs": 1}})
    scenes = engine_tests._scenes()
    train(cfg, tmp_path / "run", source=MemorySource(scenes))
    p = Predictor.load(tmp_path / "run" / "last.pt", method="learned")
    seg = p.segment(scenes[0].coord, scenes[0].color)
    model, c, dev = load_model(tmp_path / "run" / "last.pt", "cpu")
    ref = predict_scene(model, scenes[0], c.data.voxel_size, c.predict, dev)
    assert p.loaded.name == "mask3d" and np.array_equal(seg.masks, ref.masks) and np.array_equal(seg.scores, ref.scores)
    held = seg.masks.any(0)
    assert ((seg.labels >= 0) == held).all()
    with pytest.raises(DataError, match="'hybrid' works on the outputs of a segmenter model, not a mask3d model: use "
                                        "--method learned"):
        Predictor.load(tmp_path / "run" / "last.pt", method="hybrid")
    assert Predictor.load(tmp_path / "run" / "last.pt").method == "learned"  # the default step runs either model
    with pytest.raises(DataError, match="--tta"):
        Predictor.load(tmp_path / "run" / "last.pt", method="learned", tta=True)
