"""`assist3d view`: what the page is made from (generated scenes, scans, FORMAT:PATH, segment outputs,
predictions), a self-contained page whose data round-trips, where it is written, and, in a real
headless Chromium, a page that loads without console errors, draws a non-blank picture, changes it
on a toggle and answers a hover."""

from __future__ import annotations

import base64
import io
import json
import re
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from assist3d.bench.evaluation.predictions import save_predictions
from assist3d.cli import app
from assist3d.core.contracts import PlacedInstance, PointSample, Room, SceneLayout
from assist3d.core.errors import ConfigError, DataError
from assist3d.export import write_scene
from assist3d.view import labels_from_masks, load_view, page_html, subsample
from assist3d.view.sources import SCANNET20_NAMES, ViewData

from headless import Chromium, find_chromium

plotly_missing = pytest.mark.skipif(
    __import__("importlib").util.find_spec("plotly") is None, reason="plotly (the [view] extra) not installed")
runner = CliRunner()


def _pose(x, y):
    p = np.eye(4)
    p[0, 3], p[1, 3] = x, y
    return p


def _scene(root: Path, name="scene_000000", n=400, seed=0) -> Path:
    rng = np.random.default_rng(seed)
    inst = rng.integers(-1, 3, n).astype(np.int32)
    sample = PointSample(name, rng.random((n, 3), dtype=np.float32), rng.integers(0, 255, (n, 3), dtype=np.uint8),
                         rng.random((n, 3), dtype=np.float32), inst, np.where(inst >= 0, inst % 2, -1).astype(np.int32),
                         np.ones(n, bool))
    layout = SceneLayout(Room(((0.0, 0.0), (3.0, 0.0), (3.0, 3.0), (0.0, 3.0)), 2.5),
                         (PlacedInstance(0, "a", "sofa", "floor", _pose(1, 1)),
                          PlacedInstance(1, "b", "lamp", "floor", _pose(2, 2))), (), 5, 0.1,
                         classes=("sofa", "lamp"))
    write_scene(root / name, sample, layout, {"id": name, "seed": 5})
    return root / name


def _array_scan(path: Path, n: int, seed=0, objects=30) -> np.ndarray:
    """An (N, 8) room scan: floor and two walls (void), and boxes of ScanNet classes 3..20."""
    rng = np.random.default_rng(seed)
    a = np.zeros((n, 8), np.float32)
    kind = rng.integers(0, 3 + objects, n)  # 0 floor, 1, 2 walls, else an object
    u, v = rng.random(n), rng.random(n)
    a[:, 0], a[:, 1], a[:, 2] = 6 * u, 5 * v, 0
    a[kind == 1, 1], a[kind == 1, 2] = 5, 2.5 * v[kind == 1]
    a[kind == 2, 0], a[kind == 2, 2] = 0, 2.5 * u[kind == 2]
    obj = kind >= 3
    k = kind[obj] - 3
    centre = np.stack([0.6 + (k % 6) * 0.95, 0.6 + (k // 6) * 0.9], 1)
    a[obj, 0] = centre[:, 0] + 0.6 * (u[obj] - 0.5)
    a[obj, 1] = centre[:, 1] + 0.6 * (v[obj] - 0.5)
    a[obj, 2] = rng.random(obj.sum()) * (0.4 + 0.05 * (k % 10))
    a[:, 3:6] = rng.integers(60, 200, (n, 3))
    a[:, 6] = np.where(obj, 3 + (kind - 3) % 18, np.where(kind == 0, 2, 1))
    a[:, 7] = kind + 1
    np.save(path, a)
    return a


def _prediction(path: Path, a: np.ndarray, seed=1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    ids = np.unique(a[a[:, 6] >= 3, 7])
    masks = np.stack([a[:, 7] == i for i in ids[rng.permutation(len(ids))]])
    scores = np.linspace(0.95, 0.2, len(masks)).astype(np.float32)
    save_predictions(path, masks, scores)
    return masks, scores


def _payload(page: str) -> dict:
    m = re.search(r'<script id="view-data" type="application/json">(.*?)</script>', page, re.S)
    assert m, "no data element"
    return json.loads(m.group(1))


def _arr(s: str, dtype) -> np.ndarray:
    return np.frombuffer(base64.b64decode(s), dtype=dtype)


# ----------------------------------------------------------------------------------------------- sources


def test_labels_from_masks_take_the_best_scoring_mask_and_leave_uncovered_points_out():
    masks = np.array([[1, 1, 0, 0, 0], [0, 1, 1, 0, 0], [0, 0, 0, 0, 1]], bool)
    scores = np.array([0.2, 0.9, 0.5], np.float32)
    assert labels_from_masks(masks, scores).tolist() == [0, 1, 1, -1, 2]
    assert labels_from_masks(np.zeros((0, 3), bool), np.zeros(0, np.float32)).tolist() == [-1, -1, -1]


def test_a_generated_scene_brings_its_instances_classes_and_class_names(tmp_path):
    d = _scene(tmp_path / "ds")
    (tmp_path / "ds" / "manifest.json").write_text("{}")
    for path in (d, tmp_path / "ds"):  # the scene folder or its dataset
        v = load_view(str(path))
        assert v.name == "scene_000000" and len(v) == 400
        assert np.array_equal(v.instance, np.load(d / "instance.npy"))
        assert np.array_equal(v.klass, np.load(d / "segment.npy"))
        assert v.class_names == ("sofa", "lamp") and v.rgb is not None and v.pred is None
    with pytest.raises(DataError, match="no such scene"):
        load_view(str(tmp_path / "ds"), scene="scene_000009")


def test_a_scan_with_a_prediction_and_non_finite_points_stays_aligned(tmp_path):
    a = _array_scan(tmp_path / "scan.npy", 500)
    masks, scores = _prediction(tmp_path / "p.npz", a)
    raw = a[:, :6].copy()
    raw[7] = np.nan  # a raw (N, 6) scan may hold non-finite points: the prediction covers every row
    np.save(tmp_path / "raw.npy", raw)
    v = load_view(str(tmp_path / "raw.npy"), pred=tmp_path / "p.npz")
    keep = np.ones(500, bool)
    keep[7] = False
    assert len(v) == 499 and np.array_equal(v.pred, labels_from_masks(masks, scores)[keep])
    assert np.array_equal(v.coord, raw[keep, :3])
    assert any("non-finite" in n for n in v.notes)
    # an (N, 8) scan carries ground truth with ScanNet-20 names
    g = load_view(str(tmp_path / "scan.npy"))
    assert g.class_names == SCANNET20_NAMES and (g.instance >= 0).any() and g.klass.max() <= 19
    with pytest.raises(DataError, match="500"):  # a prediction over other points is refused, naming the file
        save_predictions(tmp_path / "short.npz", masks[:, :400], scores)
        load_view(str(tmp_path / "scan.npy"), pred=tmp_path / "short.npz")


def test_a_segment_output_is_read_from_its_npz_and_the_ply_beside_it(tmp_path):
    from assist3d.data.ply import write_ply

    a = _array_scan(tmp_path / "scan.npy", 300)
    seg = tmp_path / "seg"
    seg.mkdir()
    masks, scores = _prediction(seg / "scan.npz", a)
    write_ply(seg / "scan.ply", a[:, :3], a[:, 3:6].astype(np.uint8))
    for path in (seg / "scan.npz", seg):  # the file, or the folder of segment outputs
        v = load_view(str(path))
        assert np.array_equal(v.pred, labels_from_masks(masks, scores)) and np.allclose(v.coord, a[:, :3])
    (seg / "scan.ply").unlink()
    with pytest.raises(DataError, match="scan.ply beside it"):
        load_view(str(seg / "scan.npz"))


def test_dataset_specs_open_through_their_reader(tmp_path):
    _array_scan(tmp_path / "a.npy", 200, seed=1)
    _array_scan(tmp_path / "b.npy", 250, seed=2)
    assert len(load_view(f"array:{tmp_path}")) == 200
    assert len(load_view(f"array:{tmp_path}", scene="b")) == 250
    with pytest.raises(DataError, match="no scene"):
        load_view(f"array:{tmp_path}", scene="c")
    with pytest.raises(DataError, match="not found"):
        load_view(str(tmp_path / "missing.ply"))


def test_subsample_is_seeded_and_keeps_every_array_aligned():
    rng = np.random.default_rng(0)
    n = 1000
    inst = rng.integers(-1, 9, n).astype(np.int32)
    v = ViewData("s", rng.random((n, 3)).astype(np.float32), rng.integers(0, 255, (n, 3), dtype=np.uint8),
                 inst, inst.copy(), (), inst.copy())
    a, b = subsample(v, 300, seed=3), subsample(v, 300, seed=3)
    assert len(a) == 300 and np.array_equal(a.coord, b.coord)
    assert not np.array_equal(a.coord, subsample(v, 300, seed=4).coord)
    idx = [int(np.flatnonzero((v.coord == c).all(1))[0]) for c in a.coord[:20]]
    assert np.array_equal(a.instance[:20], inst[idx]) and np.array_equal(a.pred[:20], inst[idx])
    assert np.array_equal(a.rgb[:20], v.rgb[idx]) and "300 of 1,000" in a.notes[-1]
    assert subsample(v, 0) is v and subsample(v, 5000) is v


# ----------------------------------------------------------------------------------------------- the page


@plotly_missing
def test_the_page_is_self_contained_and_its_data_round_trips():
    rng = np.random.default_rng(0)
    n = 50
    inst = rng.integers(-1, 5, n).astype(np.int32)
    evil = "</script><script>alert(1)</script>"
    v = ViewData("s<1>", rng.random((n, 3)).astype(np.float32), rng.integers(0, 255, (n, 3), dtype=np.uint8),
                 inst, np.where(inst >= 0, 0, -1).astype(np.int32), (evil,), inst[::-1].copy(),
                 np.linspace(1, 0, 5).astype(np.float32))
    page = page_html(v, color="class")
    # nothing loaded from elsewhere: no external scripts, styles or frames
    assert not re.search(r"<(script|link|iframe|img)[^>]+(src|href)=", page)
    assert "Plotly" in page and page.count("</script>") == 3  # plotly.js, the data, the viewer
    assert evil not in page and "<title>assist3d view: s&lt;1&gt;</title>" in page
    d = _payload(page)
    assert d["classNames"] == [evil] and d["color"] == "class" and d["n"] == n
    for key, src in (("x", v.coord[:, 0]), ("y", v.coord[:, 1]), ("z", v.coord[:, 2])):
        assert np.array_equal(_arr(d[key], "<f4"), src)
    assert np.array_equal(_arr(d["rgb"], "u1").reshape(-1, 3), v.rgb)
    assert np.array_equal(_arr(d["instance"], "<i4"), inst) and np.array_equal(_arr(d["pred"], "<i4"), inst[::-1])
    assert len(d["palette"]) == 5 and all(re.fullmatch(r"#[0-9a-f]{6}", c) for c in d["palette"])


@plotly_missing
def test_the_page_refuses_a_colouring_the_input_cannot_give():
    v = ViewData("scan", np.zeros((3, 3), np.float32), np.zeros((3, 3), np.uint8))
    with pytest.raises(ConfigError, match="no prediction"):
        page_html(v, color="prediction")
    with pytest.raises(ConfigError, match="side by side|--side-by-side"):
        page_html(v, side_by_side=True)
    with pytest.raises(ConfigError, match="expected one of"):
        page_html(v, color="depth")
    assert _payload(page_html(v))["color"] == "rgb"


def test_without_the_extra_the_command_says_how_to_install_it(tmp_path, monkeypatch):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "plotly" else real(name, *a))
    _array_scan(tmp_path / "scan.npy", 100)
    with pytest.raises(ConfigError, match=r"assist3d\[view\]"):
        runner.invoke(app, ["view", str(tmp_path / "scan.npy")], catch_exceptions=False)


@plotly_missing
def test_view_writes_beside_the_input_never_into_a_dataset(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    ds = tmp_path / "ds"
    _scene(ds)
    (ds / "manifest.json").write_text("{}")
    before = sorted(p.relative_to(ds) for p in ds.rglob("*"))
    for arg in ("ds", "ds/scene_000000", str(ds)):
        res = runner.invoke(app, ["view", arg, "--json"], catch_exceptions=False)
        assert res.exit_code == 0, res.output
        row = json.loads(res.stdout)
        assert Path(row["html"]).resolve() == tmp_path / "ds_scene_000000.html"
        assert row["points"] == 400 and row["colors"] == ["rgb", "instance", "class"]
    assert sorted(p.relative_to(ds) for p in ds.rglob("*")) == before
    a = _array_scan(tmp_path / "scan.npy", 300)
    _prediction(tmp_path / "p.npz", a)
    res = runner.invoke(app, ["view", "scan.npy", "--pred", "p.npz", "--side-by-side", "--max-points", "100"],
                        catch_exceptions=False)
    assert res.exit_code == 0 and "scan.html" in res.stdout and "100 points" in res.stdout
    d = _payload((tmp_path / "scan.html").read_text())
    assert d["sideBySide"] and d["n"] == 100 and d["color"] == "instance"
    out = tmp_path / "o" / "x.html"
    res = runner.invoke(app, ["view", f"array:{tmp_path}", "--out", str(out), "--color", "rgb"])
    assert res.exit_code == 0 and _payload(out.read_text())["color"] == "rgb"


# ----------------------------------------------------------------------------------------------- the browser

BROWSER = find_chromium()


def _png(data: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB")).astype(np.int16)


@pytest.mark.slow
@plotly_missing
@pytest.mark.skipif(BROWSER is None, reason="no Chromium to test the page in (apt-get install chromium)")
def test_the_page_in_a_headless_browser(tmp_path):
    """300,000 points with ground truth and a prediction: loads with no console error and no request
    beyond its own file, draws a picture, changes it on a click of "prediction" and of "side by side",
    and names the instance and class of a hovered point."""
    a = _array_scan(tmp_path / "scan.npy", 300_000)
    _prediction(tmp_path / "scan_pred.npz", a)
    page = tmp_path / "scan.html"
    res = runner.invoke(app, ["view", str(tmp_path / "scan.npy"), "--pred", str(tmp_path / "scan_pred.npz"),
                              "--out", str(page), "--point-size", "2"], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    with Chromium(BROWSER, width=800, height=560, timeout=240) as b:
        t0 = time.monotonic()
        b.open(page.as_uri())
        b.wait_for("window.assist3dView && (window.assist3dView.ready || window.assist3dView.errors.length > 0)",
                   timeout=300)
        loaded = time.monotonic() - t0
        assert b.evaluate("window.assist3dView.errors") == []
        assert b.evaluate("window.assist3dView.state.color") == "instance"
        plot = b.evaluate("(() => { const r = document.getElementById('plot').getBoundingClientRect();"
                          " return [r.left, r.top, r.right, r.bottom]; })()")
        x0, y0, x1, y1 = (int(round(c)) for c in plot)

        def shot() -> np.ndarray:
            return _png(b.screenshot())[y0:y1, x0:x1]

        first = shot()
        painted = (first < 235).any(axis=2)  # not the white page
        assert painted.mean() > 0.05, f"the plot is blank ({painted.mean():.3f} painted)"
        assert len(np.unique(first.reshape(-1, 3), axis=0)) > 30  # many instance colours, not one flat fill

        def click(selector: str) -> None:
            n = b.evaluate("window.assist3dView.draws")
            cx, cy = b.evaluate(f"(() => {{ const r = document.querySelector('{selector}').getBoundingClientRect();"
                                " return [r.left + r.width / 2, r.top + r.height / 2]; })()")
            b.click(cx, cy)
            b.wait_for(f"window.assist3dView.draws > {n}", timeout=180)
            time.sleep(0.5)

        click("button[data-color=prediction]")
        assert b.evaluate("window.assist3dView.state.color") == "prediction"
        second = shot()
        changed = (np.abs(second - first).sum(axis=2) > 30).mean()
        assert changed > 0.02, f"the prediction toggle changed {changed:.4f} of the plot"

        click("#side")
        assert b.evaluate("window.assist3dView.state.side") is True
        third = shot()
        assert (np.abs(third - second).sum(axis=2) > 30).mean() > 0.02
        assert b.evaluate("document.getElementById('titles').className") == "on"
        # one camera: turning the ground-truth pane turns the prediction pane with it
        b.evaluate("Plotly.relayout(document.getElementById('plot'), {'scene.camera': {eye: {x: 0.4, y: -1.9, z: 0.9},"
                   " up: {x: 0, y: 0, z: 1}, center: {x: 0, y: 0, z: 0}}}).then(() => true)", timeout=180)
        b.wait_for("(() => { const c = document.getElementById('plot').layout.scene2.camera;"
                   " return !!c && Math.abs(c.eye.x - 0.4) < 1e-9 && Math.abs(c.eye.y + 1.9) < 1e-9; })()", timeout=180)
        third = shot()

        # hover over painted pixels until the page names a point (both panes name both labellings)
        ys, xs = np.nonzero((np.abs(third - third[5, 5]).sum(axis=2) > 60))
        rng = np.random.default_rng(0)
        text = None
        for k in rng.permutation(len(xs))[:25]:
            b.move(x0 + int(xs[k]), y0 + int(ys[k]))
            for _ in range(6):
                time.sleep(0.3)
                text = b.evaluate("(() => { const t = document.getElementById('tip');"
                                  " return t.style.display === 'block' ? t.innerText : null; })()")
                if text:
                    break
            if text:
                break
        assert text and "class: " in text and ("instance" in text or "background" in text), text
        assert "predicted instance" in text, text
        timings = b.evaluate("window.assist3dView.timings")
    assert b.console_errors == [] and b.exceptions == []
    assert all(u.startswith("file:") for u in b.requests), b.requests  # no network at view time
    print(f"300k points: ready {loaded:.1f} s, draws {timings['drawMs']} ms (headless, software WebGL)")


@plotly_missing
def test_the_real_scan_opens_with_its_labels(real_scan_path, tmp_path):
    v = load_view(str(real_scan_path))
    raw = np.load(real_scan_path)
    assert len(v) == len(raw) == 107_046 and np.allclose(v.coord, raw[:, :3])
    objects = np.unique(v.instance[v.instance >= 0])
    assert 10 <= len(objects) <= 46 and v.class_names[v.klass[v.instance >= 0][0]] != "wall"
    d = _payload(page_html(v))
    assert d["n"] == 107_046 and d["color"] == "instance" and d["classNames"][0] == "wall"
