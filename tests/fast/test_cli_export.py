"""The small things a user meets around a dataset: `show` writes beside the dataset and its labels do
not overlap; `export ply` turns a whole dataset into PLY files; `generate --ply` on a finished dataset
adds the missing points.ply (the same bytes a fresh --ply run writes) or says why not."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from assist3d.cli import app
from assist3d.core.contracts import PlacedInstance, PointSample, Room, SceneLayout
from assist3d.core.errors import ConfigError, DataError
from assist3d.export import ply_bytes, read_scene_meta, write_scene
from assist3d.export.preview import beside_dataset, place_labels

runner = CliRunner()


def _pose(x, y):
    p = np.eye(4)
    p[0, 3], p[1, 3] = x, y
    return p


def _crowded_scene(root: Path, name="scene_000000", objects=24, seed=0) -> Path:
    """A 3 x 3 m room with ``objects`` small floor objects packed together (their labels would clump)."""
    rng = np.random.default_rng(seed)
    per = 60
    centres = [(1.0 + 0.25 * (k % 5), 1.0 + 0.25 * (k // 5)) for k in range(objects)]
    coord = np.concatenate([np.c_[rng.uniform(cx - 0.1, cx + 0.1, per), rng.uniform(cy - 0.1, cy + 0.1, per),
                                  rng.uniform(0, 0.8, per)] for cx, cy in centres]).astype(np.float32)
    n = len(coord)
    inst = np.repeat(np.arange(objects, dtype=np.int32), per)
    normal = np.tile(np.array([[0, 0, 1]], np.float32), (n, 1))
    sample = PointSample(name, coord, rng.integers(0, 255, (n, 3), dtype=np.uint8), normal, inst, inst % 3,
                         np.ones(n, bool))
    insts = tuple(PlacedInstance(k, f"a{k}", ("armchair", "bookshelf", "coffee table")[k % 3], "floor",
                                 _pose(*centres[k])) for k in range(objects))
    layout = SceneLayout(Room(((0.0, 0.0), (3.0, 0.0), (3.0, 3.0), (0.0, 3.0)), 2.5), insts, (), 5, 0.1,
                         classes=("armchair", "bookshelf", "coffee table"))
    write_scene(root / name, sample, layout, {"id": name, "seed": 5})
    return root / name


def _dataset(root: Path, scenes=2) -> Path:
    for i in range(scenes):
        _crowded_scene(root, f"scene_{i:06d}", seed=i)
    (root / "manifest.json").write_text(json.dumps({"format": "assist3d-dataset", "classes": []}))
    return root


def _tree(root: Path) -> dict[str, bytes]:
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*")) if p.is_file()}


# ----------------------------------------------------------------------------------------------- show


def test_labels_never_overlap_and_the_crowded_ones_are_counted():
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = Figure(figsize=(4, 4), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    ax.set_xlim(0, 3)
    ax.set_ylim(0, 3)
    rng = np.random.default_rng(0)
    labels = [(1.5 + 0.05 * rng.standard_normal(), 1.5 + 0.05 * rng.standard_normal(), f"object {k}", float(k))
              for k in range(40)]  # forty labels on one spot: the clump the old preview drew
    renderer = fig.canvas.get_renderer()
    written, left_out = place_labels(ax, labels, renderer)
    boxes = [t.get_window_extent(renderer) for t in written]
    assert len(written) + left_out == 40 and len(written) >= 8 and left_out > 0
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            assert not boxes[i].overlaps(boxes[j]), (written[i].get_text(), written[j].get_text())
    frame = ax.get_window_extent(renderer)
    assert all(frame.x0 <= b.x0 and b.x1 <= frame.x1 and frame.y0 <= b.y0 and b.y1 <= frame.y1 for b in boxes)
    assert written[0].get_text() == "object 39"  # the highest priority (largest object) goes first
    spread = [(2.5 * k / 5 + 0.25, 0.5 + 2 * (k % 2)) for k in range(5)]  # apart: every label on its object
    ax2 = fig.add_subplot(2, 2, 4)
    ax2.set_xlim(0, 3)
    ax2.set_ylim(0, 3)
    written, left_out = place_labels(ax2, [(x, y, "lamp", 1.0) for x, y in spread], renderer, fontsize=4)
    assert left_out == 0 and [t.get_position() for t in written] == spread
    for t, anchor in zip(written, spread):  # at the anchor itself, not moved aside
        b = t.get_window_extent(renderer)
        assert np.allclose([(b.x0 + b.x1) / 2, (b.y0 + b.y1) / 2], ax2.transData.transform(anchor), atol=1.5)


@pytest.mark.slow
def test_show_writes_beside_the_dataset_unless_told(tmp_path, monkeypatch):
    ds = _dataset(tmp_path / "ds", scenes=1)
    before = _tree(ds)
    res = runner.invoke(app, ["show", str(ds)], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    png = tmp_path / "ds_scene_000000_preview.png"
    assert res.stdout.strip() == str(png) and png.read_bytes()[:4] == b"\x89PNG"
    assert _tree(ds) == before  # nothing written into the dataset
    res = runner.invoke(app, ["show", str(ds / "scene_000000")], catch_exceptions=False)
    assert res.stdout.strip() == str(png)
    told = ds / "preview.png"
    res = runner.invoke(app, ["show", str(ds), "--out", str(told)], catch_exceptions=False)
    assert res.exit_code == 0 and told.is_file()  # told: where the user says
    monkeypatch.chdir(ds)  # `show .` inside the dataset: still beside it
    assert beside_dataset(".", "scene_000000", ".png") == tmp_path / "ds_scene_000000.png"
    lone = _crowded_scene(tmp_path / "loose", "my_scene")  # a scene folder in no dataset: beside it
    assert beside_dataset(lone, "my_scene", "_preview.png") == tmp_path / "loose" / "my_scene_preview.png"


# ----------------------------------------------------------------------------------------------- export ply


def test_export_ply_writes_a_whole_dataset_elsewhere_or_into_its_scenes(tmp_path):
    from assist3d.data.ply import read_ply

    ds = _dataset(tmp_path / "ds", scenes=3)
    arrays_before = {k: v for k, v in _tree(ds).items() if k.endswith(".npy")}
    out = tmp_path / "plys"
    res = runner.invoke(app, ["export", "ply", str(ds), "--out", str(out), "--json"], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    row = json.loads(res.stdout)
    assert row["written"] == [str(out / f"scene_{i:06d}.ply") for i in range(3)] and row["kept"] == []
    v = read_ply(out / "scene_000001.ply").vertex
    assert np.array_equal(v["instance"], np.load(ds / "scene_000001" / "instance.npy"))
    assert np.array_equal(v["segment"], np.load(ds / "scene_000001" / "segment.npy"))
    assert np.allclose(np.c_[v["x"], v["y"], v["z"]], np.load(ds / "scene_000001" / "coord.npy"))
    rgb = runner.invoke(app, ["export", "ply", str(ds), "--out", str(tmp_path / "rgb"), "--color-by", "rgb",
                              "--scene", "scene_000002"], catch_exceptions=False)
    assert rgb.exit_code == 0 and sorted(p.name for p in (tmp_path / "rgb").iterdir()) == ["scene_000002.ply"]
    v = read_ply(tmp_path / "rgb" / "scene_000002.ply").vertex
    assert np.array_equal(np.c_[v["red"], v["green"], v["blue"]], np.load(ds / "scene_000002" / "color.npy"))
    # without --out: points.ply in each scene, listed in its marker like `generate --ply` does
    res = runner.invoke(app, ["export", "ply", str(ds)], catch_exceptions=False)
    assert res.exit_code == 0 and "3 written" in res.stdout
    for i in range(3):
        d = ds / f"scene_{i:06d}"
        meta = read_scene_meta(d)
        assert meta is not None and "points.ply" in meta["files"]
    assert {k: v for k, v in _tree(ds).items() if k.endswith(".npy")} == arrays_before
    again = runner.invoke(app, ["export", "ply", str(ds), "--json"], catch_exceptions=False)
    assert json.loads(again.stdout)["kept"] == [str(ds / f"scene_{i:06d}" / "points.ply") for i in range(3)]
    with pytest.raises(DataError, match="nothing: not found"):
        runner.invoke(app, ["export", "ply", str(tmp_path / "nothing")], catch_exceptions=False)
    with pytest.raises(ConfigError, match="needs --out"):
        runner.invoke(app, ["export", "ply", str(ds), "--color-by", "rgb"], catch_exceptions=False)
    # an unfinished scene is named and skipped, the others exported, the exit status 1
    (ds / "scene_000001" / "meta.json").unlink()
    res = runner.invoke(app, ["export", "ply", str(ds), "--out", str(tmp_path / "part"), "--json"])
    assert res.exit_code == 1 and json.loads(res.stdout)["skipped"].keys() == {"scene_000001"}
    assert sorted(p.name for p in (tmp_path / "part").iterdir()) == ["scene_000000.ply", "scene_000002.ply"]


def test_a_scene_ply_from_its_arrays_is_the_ply_generation_writes(tmp_path):
    """`generate --ply` on a finished dataset and `export ply` rebuild points.ply from the arrays: the
    very bytes a run with --ply from the start writes."""
    from assist3d.export.writer import export_scene_ply, load_scene_arrays

    d = _crowded_scene(tmp_path / "ds")
    a = load_scene_arrays(d)
    sample = PointSample("s", a["coord"], a["color"], a["normal"], a["instance"], a["segment"],
                         np.ones(len(a["coord"]), bool))
    assert export_scene_ply(d) is True and (d / "points.ply").read_bytes() == ply_bytes(sample)
    assert export_scene_ply(d) is False  # there already
    meta = read_scene_meta(d)
    assert meta["files"]["points.ply"]["bytes"] == len(ply_bytes(sample))
