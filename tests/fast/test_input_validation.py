"""Readers and importers on bad content: refused with a DataError naming the file, or cleaned with a
warning that says what changed (the per-reader policy of docs/evaluation.md, "Input validation")."""

from __future__ import annotations

import io
import json
import logging
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator

import numpy as np
import pytest

from assist3d.data import open_dataset
from assist3d.data.ply import write_ply
from assist3d.core.errors import ConfigError, DataError


class _Collect(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


@contextmanager
def warnings_of(name: str) -> Iterator[list[str]]:
    """Warnings logged under logger ``name`` (whatever the package logger's propagation is)."""
    handler = _Collect()
    logger = logging.getLogger(name)
    logger.addHandler(handler)
    try:
        yield handler.messages
    finally:
        logger.removeHandler(handler)


def _scene(n: int = 6) -> np.ndarray:
    """An (n, 8) float32 array scene: chairs (semantic 5) with instance ids 1..n."""
    a = np.zeros((n, 8), np.float32)
    a[:, :3] = np.arange(n * 3).reshape(n, 3) * 0.1
    a[:, 3:6] = 100
    a[:, 6] = 5
    a[:, 7] = np.arange(1, n + 1)
    return a


def _with(a: np.ndarray, row: int, col: int, value: float) -> np.ndarray:
    a = a.copy()
    a[row, col] = value
    return a


# ------------------------------------------------------------------------------------ array reader

REFUSED = {
    "nan_coord": (_with(_scene(), 2, 1, np.nan), r"1 of 6 points have non-finite coordinates.*row 2"),
    "inf_coord": (_with(_scene(), 0, 2, -np.inf), "non-finite coordinates"),
    "float32_overflow": (_with(_scene().astype(np.float64), 1, 0, 1e300), "non-finite coordinates"),
    "far_coord": (_with(_scene(), 3, 0, 1e30), r"beyond ±1e\+05 m.*re-centre"),
    "fractional_semantic": (_with(_scene(), 1, 6, 2.5), r"semantic labels \(column 6\) are not integers.*2\.5"),
    "fractional_instance": (_with(_scene(), 4, 7, 2.5), r"instance ids \(column 7\) are not integers"),
    "nan_instance": (_with(_scene(), 4, 7, np.nan), "instance ids .* are not finite"),
    "semantic_above_20": (_with(_scene(), 0, 6, 40), r"semantic labels .* above 20"),
    "semantic_negative": (_with(_scene(), 0, 6, -1), r"semantic labels .* below 0"),
    "absurd_instance": (_with(_scene(), 0, 7, 1e12), r"instance ids .* above 2147483647"),
    "empty": (np.zeros((0, 8), np.float32), r"no points"),
    "complex": (_scene().astype(np.complex64), r"numeric array.*complex64"),
    "bool": (_scene() > 0, r"numeric array.*bool"),
    "strings": (_scene().astype(str), r"numeric array.*<U"),
    "objects": (_scene().astype(object), r"Python objects"),
    "wrong_shape": (np.zeros((5, 7), np.float32), r"\(N, 8\)"),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_array_reader_refuses_bad_scans_naming_the_file(tmp_path, case):
    a, pattern = REFUSED[case]
    path = tmp_path / f"{case}.npy"
    np.save(path, a, allow_pickle=True)
    with pytest.raises(DataError, match=pattern) as err:
        open_dataset(f"array:{path}")[0]
    assert str(path) in str(err.value) and "\n" not in str(err.value)


def test_array_reader_refuses_truncated_and_forged_npy_headers(tmp_path):
    path = tmp_path / "cut.npy"
    np.save(path, _scene(50))
    path.write_bytes(path.read_bytes()[:-40])
    with pytest.raises(DataError, match=r"cut\.npy: truncated \.npy"):
        open_dataset(f"array:{path}")[0]
    forged = tmp_path / "forged.npy"
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f4", "fortran_order": False, "shape": (10**11, 8)})
    forged.write_bytes(buf.getvalue() + bytes(64))  # would allocate 3 TiB before the fix
    with pytest.raises(DataError, match=r"forged\.npy: truncated"):
        open_dataset(f"array:{forged}")[0]


def test_array_reader_cleans_colours_and_negative_instances_with_a_warning(tmp_path):
    a = _scene()
    a[1, 3], a[2, 4], a[3, 5] = 300, -5, np.nan
    a[4, 7] = -7
    path = tmp_path / "cleaned.npy"
    np.save(path, a)
    with warnings_of("assist3d.data") as msgs:
        s = open_dataset(f"array:{path}")[0]
    assert s.color[1, 0] == 255 and s.color[2, 1] == 0 and s.color[3, 2] == 0
    assert s.instance[4] == -1 and s.instance[5] == 6
    text = " | ".join(msgs)
    assert "cleaned.npy: 3 of 6 points have colour values" in text, text
    assert "cleaned.npy: 1 of 6 instance ids (column 7) are below -1" in text and "-7" in text, text


# ------------------------------------------------------------------------------------ pointcept


def _pointcept(d: Path, n: int = 5) -> Path:
    d.mkdir(parents=True)
    np.save(d / "coord.npy", np.arange(n * 3, dtype=np.float32).reshape(n, 3))
    np.save(d / "segment20.npy", np.array([4, 4, 5, 5, 6][:n], np.int64))
    np.save(d / "instance.npy", np.arange(n, dtype=np.int64))
    return d


def test_pointcept_refuses_bad_coordinates_labels_and_empty_scenes(tmp_path):
    d = _pointcept(tmp_path / "a")
    np.save(d / "coord.npy", np.array([[0, 0, 0], [np.nan, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3]], np.float32))
    with pytest.raises(DataError, match=r"a/coord\.npy: 1 of 5 points have non-finite coordinates"):
        open_dataset(f"pointcept:{d}")[0]
    d = _pointcept(tmp_path / "b")
    np.save(d / "segment20.npy", np.array([4, 4.5, 5, 5, 6]))
    with pytest.raises(DataError, match=r"b/segment20\.npy: 1 of 5 class indices are not integers"):
        open_dataset(f"pointcept:{d}")[0]
    d = _pointcept(tmp_path / "c")
    np.save(d / "segment20.npy", np.array([4, 10**9, 5, 5, 6]))
    with pytest.raises(DataError, match=r"c/segment20\.npy: 1 of 5 class indices are above 65535"):
        open_dataset(f"pointcept:{d}")[0]
    d = _pointcept(tmp_path / "d")
    np.save(d / "instance.npy", np.array(["a", "b", "c", "d", "e"]))
    with pytest.raises(DataError, match=r"d/instance\.npy: instance ids must be real numbers"):
        open_dataset(f"pointcept:{d}")[0]
    d = _pointcept(tmp_path / "e")
    np.save(d / "coord.npy", np.zeros((0, 3), np.float32))
    with pytest.raises(DataError, match=r"e/coord\.npy: no points"):
        open_dataset(f"pointcept:{d}")[0]


def test_pointcept_cleans_ignore_indices_and_bad_normals_with_warnings(tmp_path):
    d = _pointcept(tmp_path / "s")
    np.save(d / "instance.npy", np.array([0, -100, 1, -1, 2]))
    np.save(d / "segment20.npy", np.array([4, -100, 5, 5, 6]))
    normal = np.tile(np.array([0, 0, 1], np.float32), (5, 1))
    normal[2] = np.nan
    np.save(d / "normal.npy", normal)
    with warnings_of("assist3d.data") as msgs:
        s = open_dataset(f"pointcept:{d}")[0]
    assert s.instance.tolist() == [0, -1, 1, -1, 2] and s.segment.tolist() == [4, -1, 5, 5, 6]
    assert s.normal[2].tolist() == [0, 0, 0] and s.normal[0].tolist() == [0, 0, 1]
    text = " | ".join(msgs)
    assert "1 of 5 instance ids are below -1" in text and "1 of 5 class indices are below -1" in text, text
    assert "normal.npy: 1 of 5 points have non-finite normals" in text, text


# ------------------------------------------------------------------------------------ scannet, s3dis

GRID = np.array([[x, y, 0.0] for y in range(2) for x in range(4)], np.float32)
FACES = np.array([[0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6]])
TSV = "id\traw_category\tcategory\tcount\tnyu40id\n1\tchair\tchair\t1\t5\n"


def _scannet(root: Path, segs: list, groups: list, coord: np.ndarray = GRID) -> Path:
    d = root / "scene0000_00"
    d.mkdir(parents=True)
    write_ply(d / "scene0000_00_vh_clean_2.ply", coord, None, FACES)
    (d / "scene0000_00_vh_clean_2.0.010000.segs.json").write_text(json.dumps({"segIndices": segs}))
    (d / "scene0000_00.aggregation.json").write_text(json.dumps({"segGroups": groups}))
    (root / "scannetv2-labels.combined.tsv").write_text(TSV)
    return d


def test_scannet_refuses_non_integer_segments_and_non_finite_vertices(tmp_path):
    group = [{"objectId": 0, "segments": [1], "label": "chair"}]
    _scannet(tmp_path / "a", [1, 1, 1, 1, 2.5, 2, 2, 2], group)
    with pytest.raises(DataError, match=r"segs\.json: 'segIndices' holds 1 values that are not integers.*2\.5"):
        open_dataset(f"scannet:{tmp_path / 'a'}")[0]
    _scannet(tmp_path / "b", [1, 1, 1, 1, "x", 2, 2, 2], group)
    with pytest.raises(DataError, match=r"segs\.json: 'segIndices' must be a flat list of integers"):
        open_dataset(f"scannet:{tmp_path / 'b'}")[0]
    _scannet(tmp_path / "c", [1] * 8, [{"objectId": "zero", "segments": [1], "label": "chair"}, *group])
    with pytest.raises(DataError, match=r"aggregation\.json: segGroups objectId 'zero' is not an integer"):
        open_dataset(f"scannet:{tmp_path / 'c'}")[0]
    _scannet(tmp_path / "d", [1] * 8, [{"objectId": 0, "segments": [1, [2]], "label": "chair"}])
    with pytest.raises(DataError, match=r"aggregation\.json: 'segments' must be a flat list of integers"):
        open_dataset(f"scannet:{tmp_path / 'd'}")[0]
    bad = GRID.copy()
    bad[3, 2] = np.inf
    _scannet(tmp_path / "e", [1] * 8, group, coord=bad)
    with pytest.raises(DataError, match=r"vh_clean_2\.ply: 1 of 8 points have non-finite vertex coordinates"):
        open_dataset(f"scannet:{tmp_path / 'e'}")[0]


def test_s3dis_refuses_overflowing_coordinates_and_empty_rooms(tmp_path):
    anno = tmp_path / "Area_1" / "office_1" / "Annotations"
    anno.mkdir(parents=True)
    (anno / "chair_1.txt").write_text("1 2 3 10 20 30\n1e39 2 3 10 20 30\n")
    with pytest.raises(DataError, match=r"chair_1\.txt: 1 of 2 points have non-finite coordinates"):
        open_dataset(f"s3dis:{tmp_path}")[0]
    (anno / "chair_1.txt").write_text("")
    with pytest.raises(DataError, match=r"Annotations: no points"):
        open_dataset(f"s3dis:{tmp_path}")[0]
    (anno / "chair_1.txt").write_text("1 2 3 10 20 300\n")
    with warnings_of("assist3d.data") as msgs:
        s = open_dataset(f"s3dis:{tmp_path}")[0]
    assert s.color[0].tolist() == [10, 20, 255] and any("chair_1.txt: 1 of 1 points" in m for m in msgs), msgs


# ------------------------------------------------------------------------------------ evaluate


def test_evaluate_warns_on_scenes_whose_labels_are_all_void(tmp_path):
    from assist3d.bench.evaluation import evaluate_dataset, save_predictions

    gt = tmp_path / "gt"
    gt.mkdir()
    void = _scene(300)
    void[:, 6] = 0  # no ScanNet-20 class: every point void
    np.save(gt / "void_scene.npy", void)
    good = _scene(300)
    good[:, 7] = 1  # one chair of 300 points
    np.save(gt / "good_scene.npy", good)
    pred = tmp_path / "pred"
    pred.mkdir()
    for sid in ("void_scene", "good_scene"):
        save_predictions(pred / f"{sid}.npz", np.ones((1, 300), bool), np.ones(1, np.float32))
    with warnings_of("assist3d.bench.evaluation") as msgs:
        result = evaluate_dataset(open_dataset(f"array:{gt}"), pred)
    assert any("1 of 2 scenes have no ground-truth object" in m and "void_scene" in m for m in msgs), msgs
    assert np.isnan(result.per_scene["void_scene"]["AP"]) and result.per_scene["good_scene"]["AP"] == 1.0
    d = result.to_dict(per_scene=True)
    assert d["per_scene"]["void_scene"]["AP"] is None and d["AP"] == 1.0


# ------------------------------------------------------------------------------------ segment inputs


def test_segment_raw_inputs_refuse_non_numbers_and_clean_colours(tmp_path):
    from assist3d.data.scanfile import read_scan
    from assist3d.learn.segmenter.predictor import usable_points

    path = tmp_path / "scan.npy"
    np.save(path, np.zeros((4, 3), np.complex128))
    with pytest.raises(DataError, match=r"scan\.npy: expected a numeric"):
        read_scan(path)
    a = np.zeros((4, 6))
    a[:, :3] = np.arange(12).reshape(4, 3)
    a[0, 0], a[1, 1], a[2, 3] = np.nan, 1e30, np.nan
    np.save(path, a)
    with warnings_of("assist3d") as msgs:
        scan = read_scan(path)
        sid, coord, color, sample = scan.scene_id, scan.coord, scan.color, scan.sample
        ok = usable_points(str(path), sid, coord)
    assert sid == "scan" and sample is None and color.dtype == np.uint8 and color[2, 0] == 0
    assert ok.tolist() == [False, False, True, True]
    assert any("2 of 4 points" in m for m in msgs) and any("scan.npy: 1 of 4 points have colour" in m for m in msgs)
    with pytest.raises(DataError, match="no point has finite coordinates"):
        usable_points(str(path), sid, np.full((3, 3), np.inf, np.float32))


def test_segment_coordinate_limit_is_taken_in_the_scans_units():
    """The ±1e5 m limit on coordinates holds in metres whatever --units says: a point 150 m out is
    kept in a millimetre scan (1.5e5 mm) and dropped when the same numbers are read as metres."""
    from assist3d.learn.segmenter.predictor import usable_points

    coord = np.array([[0.0, 0.0, 0.0], [1.5e5, 0.0, 0.0], [2.0e8, 0.0, 0.0]], np.float32)
    assert usable_points("scan", "s", coord, "mm").tolist() == [True, True, False]
    assert usable_points("scan", "s", coord, "m").tolist() == [True, False, False]


# ------------------------------------------------------------------------------------ OBJ import

BOX_V = "".join(f"v {x} {y} {z}\n" for x in (0, 1) for y in (0, 1) for z in (0, 1))
BOX_F = ["f 1 3 4 2", "f 5 6 8 7", "f 1 2 6 5", "f 3 7 8 4", "f 1 5 7 3", "f 2 4 8 6"]


def test_mesh_import_skips_cut_and_dangling_objs_and_warns_on_unterminated_ones(tmp_path):
    from assist3d.assets.catalog import Catalog
    from assist3d.assets.meshes import import_meshes

    folder = tmp_path / "objs"
    folder.mkdir()
    files = {
        "whole.obj": BOX_V + "\n".join(BOX_F) + "\n",
        "open.obj": BOX_V + "\n".join(BOX_F[:5]) + "\n",  # a valid open mesh (most real assets are open)
        "cut.obj": BOX_V + "\n".join(BOX_F[:4]) + "\nf 1 5",  # cut inside its last face line
        "cut_vertex.obj": "\n".join(BOX_F) + "\n" + BOX_V + "v 0.5 0.",  # cut inside a vertex line
        "dangling.obj": BOX_V + "\n".join(BOX_F) + "\nf 1 2 9\n",  # references a vertex that is not there
        "unterminated.obj": BOX_V + "\n".join(BOX_F[:5]),  # complete last line, no final newline
    }
    for name, text in files.items():
        (folder / name).write_text(text)
    manifest = tmp_path / "m.json"
    manifest.write_text(json.dumps([{"path": name, "class": "crate", "up": "+z", "front": "-y"} for name in files]))
    with warnings_of("assist3d.assets") as msgs:
        report = import_meshes(Catalog.open_or_create(tmp_path / "lib"), folder, manifest, workers=1)
    reasons = {Path(s.path.split(" (")[0]).name: s.reason for s in report.skipped}
    assert set(reasons) == {"cut.obj", "cut_vertex.obj", "dangling.obj"}, reasons
    assert "truncated file" in reasons["cut.obj"] and "holds 2 of at least 3 corners" in reasons["cut.obj"]
    assert "truncated file" in reasons["cut_vertex.obj"]
    assert "references vertex 9 but the file defines only 8 vertices" in reasons["dangling.obj"]
    assert report.total == 3
    warned = [m for m in msgs if "does not end with a newline" in m]
    assert len(warned) == 1 and "unterminated.obj" in warned[0] and "f 1 5 7 3" in warned[0], msgs


# ---------------------------------------------------------------------------- encodings and nesting


def test_configs_in_another_encoding_or_nested_deeply_are_one_line_each(tmp_path):
    """A config that is not UTF-8 (a binary file passed by mistake, a Latin-1 editor save) or nested a few
    thousand levels, and a dataset manifest nested as deeply, end in one line naming the file (they were
    UnicodeDecodeError and RecursionError tracebacks)."""
    from typer.testing import CliRunner

    from assist3d.cli import app

    runner = CliRunner()
    latin = tmp_path / "latin.yaml"
    latin.write_bytes("room:\n  name: caf\xe9\n".encode("latin-1"))
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(bytes(range(256)) * 4)
    deep = tmp_path / "deep.yaml"
    deep.write_text("a: " + "[" * 5000 + "]" * 5000 + "\n")
    for cfg, what in ((latin, "not UTF-8"), (binary, "not UTF-8"), (deep, "nested too deeply")):
        for args in (["generate", "--out", str(tmp_path / "out"), "--num-scenes", "1", "--config", str(cfg)],
                     ["bench-train", "--data", "assist3d:nowhere", "--config", str(cfg)]):
            res = runner.invoke(app, args)
            said = str(res.exception) + res.output  # the command line prints an AssistError as one line
            assert res.exit_code != 0 and isinstance(res.exception, ConfigError), (args, said)
            assert str(cfg) in said and what in said and "\n" not in str(res.exception), said
    data = tmp_path / "data"
    data.mkdir()
    (data / "manifest.json").write_text('{"a": ' + "[" * 100_000 + "]" * 100_000 + "}")
    from assist3d.export.manifest import read_manifest  # what `metrics` and the assist3d reader use

    with pytest.raises(DataError, match=r"manifest\.json: unreadable manifest \(nested too deeply"):
        read_manifest(data)
