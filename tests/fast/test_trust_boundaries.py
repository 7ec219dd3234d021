"""Trust boundaries (issue 17, items 2 and 3): paths read from inside files stay inside their
folder, and text from outside (LLM answers, file names, file contents) is shown inert: control
characters escaped, long texts cut, rich markup escaped."""

from __future__ import annotations

import itertools
import json
import logging
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from assist3d.assets.catalog import Catalog
from assist3d.config import LLMConfig
from assist3d.core.contracts import AssetRecord, MeshData
from assist3d.data import open_dataset
from assist3d.core.errors import AssetError, AssistError, DataError
from assist3d.bench.evaluation import evaluate_dataset, export_scannet_txt, import_scannet_txt
from assist3d.export.writer import file_digest, read_scene_meta
from llm_fakeserver import FakeServer, Step
from test_planning_llm_planner import FLOOR, ReversePlanner

N = 40
#: An answer that would retitle the terminal, clear the screen, return to the line start and
#: start a CSI sequence with the 8-bit introducer, if it reached a terminal raw.
EVIL = "\x1b]0;pwned\x07\x1b[2J\rFAKE: all good \x9b31m"
RAW_CONTROLS = (b"\x1b", b"\x07", b"\r", "\x9b".encode())


def _mask_lines(mask: np.ndarray) -> str:
    return "".join(f"{int(v)}\n" for v in mask)


# ------------------------------------------------------------------------------------------------
# Item 2: paths stay inside


def _prediction_with(tmp_path: Path, mask_path: str) -> Path:
    """preds/sceneA.txt naming ``mask_path``; a valid mask of N points exists at ../outside.txt."""
    preds = tmp_path / "preds"
    (preds / "pred_mask").mkdir(parents=True)
    (tmp_path / "outside.txt").write_text(_mask_lines(np.arange(N) % 2 == 0))
    txt = preds / "sceneA.txt"
    txt.write_text(f"{mask_path} 1 0.9\n")
    return txt


def _spy_reads(monkeypatch) -> list[Path]:
    """Record every file read with Path.read_bytes / read_text / open."""
    seen: list[Path] = []
    for name in ("read_bytes", "read_text", "open"):
        real = getattr(Path, name)

        def spy(self, *a, _real=real, **kw):
            seen.append(Path(self).resolve())
            return _real(self, *a, **kw)

        monkeypatch.setattr(Path, name, spy)
    return seen


@pytest.mark.parametrize("where", ["../outside.txt", "absolute", "pred_mask/../../outside.txt"])
def test_benchmark_mask_path_outside_the_folder_is_refused(tmp_path, monkeypatch, where):
    mask_path = str(tmp_path / "outside.txt") if where == "absolute" else where
    txt = _prediction_with(tmp_path, mask_path)
    seen = _spy_reads(monkeypatch)
    with pytest.raises(DataError) as err:
        import_scannet_txt(txt, N)
    msg = str(err.value)
    assert str(txt) in msg and "line 1" in msg and mask_path in msg
    assert (tmp_path / "outside.txt").resolve() not in seen


def test_evaluate_refuses_an_outside_mask_and_never_opens_it(tmp_path, monkeypatch):
    gt = tmp_path / "gt"
    gt.mkdir()
    scene = np.zeros((N, 8), np.float32)
    scene[:, 6] = 5.0  # chairs
    scene[:, 7] = np.arange(N) % 2
    np.save(gt / "sceneA.npy", scene)
    _prediction_with(tmp_path, "../outside.txt")
    seen = _spy_reads(monkeypatch)
    with pytest.raises(DataError, match=r"sceneA\.txt: line 1: path '\.\./outside\.txt' leads outside"):
        evaluate_dataset(open_dataset(f"array:{gt}"), tmp_path / "preds")
    assert (tmp_path / "outside.txt").resolve() not in seen


def test_benchmark_mask_symlinked_out_of_the_folder_is_refused(tmp_path):
    txt = _prediction_with(tmp_path, "pred_mask/link.txt")
    os.symlink(tmp_path / "outside.txt", txt.parent / "pred_mask" / "link.txt")
    with pytest.raises(DataError, match="leads outside"):
        import_scannet_txt(txt, N)


def test_benchmark_masks_inside_the_folder_still_load(tmp_path):
    masks = np.stack([np.arange(N) % 2 == 0, np.arange(N) < 5])
    txt = export_scannet_txt(tmp_path / "preds", "sceneA", masks, np.array([0.9, 0.5], np.float32))
    got, scores = import_scannet_txt(txt, N)
    assert np.array_equal(got, masks) and np.allclose(scores, [0.9, 0.5])


@pytest.mark.parametrize("scene_id", ["../evil", "a/../../evil", "..", "sub/dir"])
def test_scene_id_that_is_not_a_file_name_is_refused_when_writing(tmp_path, scene_id):
    out = tmp_path / "deep" / "preds"
    with pytest.raises(DataError, match="cannot be a file name"):
        export_scannet_txt(out, scene_id, np.ones((1, N), bool), np.ones(1, np.float32))
    written = [p for p in tmp_path.rglob("*") if p.is_file()]
    assert written == []


def _catalog_with_outside_mesh(tmp_path: Path) -> Path:
    """A catalog whose index names a mesh file one folder up (a valid mesh lies there)."""
    import trimesh

    box = trimesh.creation.box((1.0, 0.5, 0.8))
    mesh = MeshData(box.vertices.astype(np.float32), box.faces.astype(np.int32),
                    np.full((len(box.faces), 3), 200, np.uint8))
    cat = Catalog.open_or_create(tmp_path / "lib")
    rec = cat.add(AssetRecord(id="test:box", source="test", name="box", class_name="box", groups=("floor",),
                              size=(1.0, 0.5, 0.8)), mesh)
    cat.save()
    (tmp_path / "lib" / rec.mesh_file).rename(tmp_path / "outside.npz")
    index = tmp_path / "lib" / "index.json"
    data = json.loads(index.read_text())
    data["assets"][0]["mesh_file"] = "../outside.npz"
    index.write_text(json.dumps(data))
    return tmp_path / "lib"


def test_catalog_mesh_file_outside_the_catalog_is_refused(tmp_path):
    cat = Catalog.open(_catalog_with_outside_mesh(tmp_path))
    with pytest.raises(AssetError, match=r"index\.json: asset 'test:box' mesh_file: path '\.\./outside\.npz' "
                                         r"leads outside"):
        cat.load_mesh("test:box")


def test_scene_marker_listing_a_file_outside_the_scene_is_not_complete(tmp_path):
    scene = tmp_path / "out" / "scene_000000"
    scene.mkdir(parents=True)
    secret = tmp_path / "secret.bin"
    secret.write_bytes(b"not part of the dataset")
    files = {"../../secret.bin": {"bytes": secret.stat().st_size, "blake2b": file_digest(secret.read_bytes())}}
    (scene / "meta.json").write_text(json.dumps({"format": "assist3d-scene", "version": 1, "files": files}))
    assert read_scene_meta(scene) is None  # refused: treated as incomplete, regenerated on resume
    ok = {"coord.npy": {"bytes": 3, "blake2b": file_digest(b"abc")}}
    (scene / "coord.npy").write_bytes(b"abc")
    (scene / "meta.json").write_text(json.dumps({"format": "assist3d-scene", "version": 1, "files": ok}))
    assert read_scene_meta(scene) is not None


# ------------------------------------------------------------------------------------------------
# Item 3: text from outside is inert


def test_shown_escapes_every_control_character_and_cuts_long_text():
    from assist3d.core.errors import inert, shown

    controls = "".join(map(chr, range(0x20))) + "\x7f" + "".join(map(chr, range(0x80, 0xA0))) + "\u202e\u2028"
    out = shown(f"a{controls}b", limit=10_000)
    assert out.startswith("a") and out.endswith("b")
    assert all(ord(c) >= 0x20 and not 0x7F <= ord(c) <= 0x9F for c in out)
    assert "\\x1b" in out and "\\r" in out and "\\n" in out and "\\x07" in out and "\\x9b" in out
    assert "\\u202e" in out
    assert shown("plain text, ünïcode ✓") == "plain text, ünïcode ✓"
    long = shown("x" * 250)
    assert long == "x" * 200 + "… (50 more chars)"
    assert shown("\x1b" * 100, limit=10) == "\\x1b\\x1b… (98 more chars)"
    assert shown("[bold red]boo[/]", markup=True) == "\\[bold red]boo\\[/]"
    assert inert("two\nlines\x1b", keep="\n") == "two\nlines\\x1b"


def test_text_printed_through_rich_has_its_markup_escaped(tmp_path):
    """`assets stats` shows skipped paths and reasons read from the catalog index."""
    from typer.testing import CliRunner

    from assist3d.cli import app

    lib = tmp_path / "lib"
    Catalog.open_or_create(lib).save()
    index = lib / "index.json"
    data = json.loads(index.read_text())
    data["skipped"] = [{"path": "[red]evil[/red].obj\x1b[2J", "reason": f"bad file: {EVIL}", "source": "meshes"}]
    index.write_text(json.dumps(data))
    res = CliRunner().invoke(app, ["assets", "stats", "--library", str(lib)], env={"COLUMNS": "300"})
    assert res.exit_code == 0, res.output
    assert "[red]evil[/red].obj" in res.stdout  # shown literally, not as red text
    assert not any(c.decode() in res.stdout for c in RAW_CONTROLS)


def _llm_log_messages(records: list[logging.LogRecord]) -> str:
    return "\n".join(r.getMessage() for r in records)


def test_llm_answer_with_escape_codes_is_logged_inert(tmp_path, caplog):
    """Every answer path that quotes the answer (HTTP error body, a body that is not a chat
    completion, a relation name in the content) logs it escaped."""
    from assist3d.planning.llm_planner import LLMPlanner

    caplog.set_level(logging.DEBUG, logger="assist3d")
    steps = [Step(status=400, raw=EVIL.encode()),  # refused JSON mode: logged, asked again without it
             Step(raw=EVIL.encode()),  # not a chat completion
             Step(status=418, raw=EVIL.encode()),  # an HTTP error body
             Step(json.dumps({"objects": [{"index": 0, "relations": [{"relation": EVIL}]}]}))]
    with warnings.catch_warnings(record=True) as caught, FakeServer(steps) as srv:
        warnings.simplefilter("always")
        cfg = LLMConfig(base_url=srv.url, model="fake", timeout_s=2.0, retries=0, cache_dir=str(tmp_path / "llm"))
        planner = LLMPlanner(cfg, fallback=ReversePlanner())
        for _ in range(3):
            planner.plan(FLOOR, rng=np.random.default_rng(0))
    text = _llm_log_messages(caplog.records) + "".join(str(w.message) for w in caught)
    assert "\\x1b]0;pwned\\x07" in text  # the answer is shown, escaped
    for c in RAW_CONTROLS:
        assert c.decode() not in text


@pytest.mark.slow
def test_cli_run_with_an_escape_code_llm_leaves_no_raw_controls_in_its_output(tmp_path):
    """`assist3d layout` against an endpoint answering terminal escape codes in three ways."""
    answers = itertools.cycle([Step(status=400, raw=EVIL.encode()), Step(raw=EVIL.encode()),
                               Step(json.dumps({"objects": [{"index": 0, "relations": [{"relation": EVIL}]}]}))])
    cfg = tmp_path / "cfg.yaml"
    with FakeServer([], responder=lambda body: next(answers)) as srv:
        cfg.write_text(json.dumps({
            "assets": {"procedural_count": 60},
            "selection": {"floor_count": 4, "wall_count": 2, "on_top_count": 1},
            "room": {"area_min": 10.0, "area_max": 14.0},
            "llm": {"base_url": srv.url, "model": "fake", "timeout_s": 2.0, "retries": 0,
                    "cache_dir": str(tmp_path / "llm")},
        }))
        env = {**os.environ, "COLUMNS": "400", "PYTHONWARNINGS": "always"}
        run = subprocess.run([sys.executable, "-m", "assist3d", "layout", "--config", str(cfg), "--out",
                              str(tmp_path / "out"), "--no-glb"], capture_output=True, env=env, timeout=300)
        assert len(srv.requests) >= 3
    assert run.returncode == 0, run.stderr.decode(errors="replace")[-2000:]
    assert b"pwned" in run.stderr  # the answer was reported ...
    for c in RAW_CONTROLS:  # ... and none of its control characters reached the terminal
        assert c not in run.stdout and c not in run.stderr, c


def test_reader_errors_quote_file_content_inert(tmp_path):
    txt = tmp_path / "sceneA.txt"
    txt.write_text(f"pred_mask/a.txt 1 {EVIL.replace(' ', '_')}\n")
    with pytest.raises(DataError) as err:
        import_scannet_txt(txt, N)
    assert "line 1" in str(err.value) and "\\x1b]0;pwned" in str(err.value)
    assert not any(c.decode() in str(err.value) for c in RAW_CONTROLS)
    long = tmp_path / "sceneB.txt"
    long.write_text("x" * 5000 + "\n")
    with pytest.raises(AssistError, match=r"more chars\)") as err:
        import_scannet_txt(long, N)
    assert len(str(err.value)) < 600
