"""generate end to end on a tiny configuration: determinism, scene-alone regeneration, workers,
resume after SIGKILL, the manifest, --verify, show and bench."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from assist3d.cli import app
from assist3d.config import parse_config
from assist3d.export import read_scene_meta
from assist3d.pipeline import generate_dataset, run_benchmark, scene_name
from assist3d.core.rng import scene_seed

TINY = {
    "seed": 11,
    "assets": {"procedural_count": 60},
    "selection": {"floor_count": 6, "wall_count": 2, "on_top_count": 1},
    "room": {"area_min": 10.0, "area_max": 16.0},
    # the layout search also stops on a wall-clock budget, which makes layouts depend on machine
    # load; a generous budget lets its node/backtrack limits (deterministic) end it instead
    "layout": {"group_budget_s": 120.0},
    "render": {"width": 80, "height": 60, "fx": 72.2, "fy": 72.2, "vantage_points": 2, "views_per_point": 6},
}
FILES = ("coord.npy", "color.npy", "normal.npy", "instance.npy", "segment.npy")


def scene_bytes(d: Path) -> dict[str, bytes]:
    out = {f: (d / f).read_bytes() for f in FILES}
    lay = json.loads((d / "layout.json").read_text())
    lay.pop("seconds")  # wall-clock time of the layout search
    lay.get("stats", {}).pop("timing", None)
    out["layout"] = json.dumps(lay, sort_keys=True).encode()
    return out


def dataset_bytes(root: Path) -> dict[str, dict[str, bytes]]:
    return {p.name: scene_bytes(p) for p in sorted(root.glob("scene_*"))}


@pytest.fixture(scope="module")
def full_run(tmp_path_factory):
    # a module fixture runs before conftest's per-test cache isolation: point it at the same
    # isolated cache folder explicitly, never at the user's
    out = tmp_path_factory.mktemp("full")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("ASSIST3D_CACHE", str(tmp_path_factory.getbasetemp() / "assist3d-cache"))
        mp.delenv("ASSIST3D_ASSETS", raising=False)
        run = generate_dataset(parse_config(TINY), out, range(3), verify=True)
    return out, run


def test_dataset_layout_manifest_and_labels(full_run):
    out, run = full_run
    assert [m["id"] for m in run.generated] == [scene_name(i) for i in range(3)]
    man = json.loads((out / "manifest.json").read_text())
    assert man["seed"] == 11 and man["config"]["render"]["width"] == 80
    assert {"assist3d", "numpy", "trimesh", "embreex"} <= set(man["versions"])
    assert len(man["classes"]) > 5 and man["classes"] == sorted(man["classes"])
    for e, i in zip(man["scenes"], range(3)):
        assert e["id"] == scene_name(i) and e["seed"] == scene_seed(11, i)
        assert e["points"] > 1000 and e["instances"] >= 1
        assert set(e["seconds"]) == {"select", "layout", "assemble", "render", "fuse", "write"}
        assert "dropped" in e and "planner" in e
        assert e["check"]["agreement"] >= 0.999 and e["check"]["ok"]
    assert (out / "config.yaml").is_file()
    assert yaml.safe_load((out / "config.yaml").read_text())["seed"] == 11
    for d in sorted(out.glob("scene_*")):
        arrays = {k: np.load(d / f"{k}.npy") for k in ("coord", "color", "normal", "instance", "segment")}
        n = len(arrays["coord"])
        assert all(len(a) == n for a in arrays.values())
        inst, seg = arrays["instance"], arrays["segment"]
        assert np.array_equal(inst == -1, seg == -1)  # background in both or in neither
        ids = {i["id"]: i["class"] for i in json.loads((d / "layout.json").read_text())["instances"]}
        assert set(np.unique(inst[inst >= 0]).tolist()) <= set(ids)
        # segment = index of the instance's class in the dataset class list
        k = np.flatnonzero(inst >= 0)[:200]
        assert all(man["classes"][s] == ids[i] for i, s in zip(inst[k].tolist(), seg[k].tolist()))


@pytest.mark.slow
def test_scene_alone_and_with_two_workers_equal_the_full_run(full_run, tmp_path):
    out, _ = full_run
    ref = dataset_bytes(out)
    alone = tmp_path / "alone"
    generate_dataset(parse_config(TINY), alone, [2])
    got = dataset_bytes(alone)
    assert set(got) == {"scene_000002"}
    differ = [k for k, v in got["scene_000002"].items() if v != ref["scene_000002"][k]]
    assert differ == []
    pooled = tmp_path / "pooled"
    run = generate_dataset(parse_config(TINY), pooled, range(3), workers=2)
    assert len(run.generated) == 3
    assert dataset_bytes(pooled) == ref


def test_resume_skips_complete_scenes_and_redoes_broken_ones(full_run, tmp_path):
    out, _ = full_run
    import shutil

    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    (copy / "scene_000001" / "meta.json").unlink()  # unfinished scene
    raw = bytearray((copy / "scene_000002" / "coord.npy").read_bytes())
    raw[-3] ^= 0x55
    (copy / "scene_000002" / "coord.npy").write_bytes(bytes(raw))  # damaged file
    run = generate_dataset(parse_config(TINY), copy, range(3))
    assert run.skipped == [0]
    assert sorted(m["index"] for m in run.generated) == [1, 2]
    assert dataset_bytes(copy) == dataset_bytes(out)


def test_ply_on_a_finished_dataset_exports_what_is_missing_and_says_why_not_for_meshes(full_run, tmp_path, caplog):
    """`generate --ply` (and --save-mesh) again on a dataset made without them: every kept scene gets its
    points.ply, listed in its marker, the arrays untouched; the mesh, which only generation can write,
    is named as missing and why."""
    import logging
    import shutil

    from assist3d.export import ply_bytes
    from assist3d.export.writer import scene_sample

    out, _ = full_run
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    assert not list(copy.rglob("points.ply"))
    cfg = parse_config({**TINY, "output": {"ply": True, "save_mesh": True}})
    with caplog.at_level(logging.INFO, logger="assist3d"):
        run = generate_dataset(cfg, copy, range(3))
    assert run.skipped == [0, 1, 2] and run.generated == [] and run.exported == [scene_name(i) for i in range(3)]
    for i in range(3):
        d = copy / scene_name(i)
        assert (d / "points.ply").read_bytes() == ply_bytes(scene_sample(out / scene_name(i)))
        assert "points.ply" in read_scene_meta(d)["files"]
    assert dataset_bytes(copy) == dataset_bytes(out)
    assert "wrote points.ply for 3 kept scenes" in caplog.text
    assert "3 kept scenes (scene_000000, scene_000001, scene_000002) have no scene.glb" in caplog.text
    again = generate_dataset(cfg, copy, range(3))  # nothing left to add
    assert again.exported == [] and again.skipped == [0, 1, 2]


def test_other_settings_in_the_same_folder_are_refused(full_run):
    out, _ = full_run
    from assist3d.core.errors import DataError

    with pytest.raises(DataError, match="different settings"):
        generate_dataset(parse_config({**TINY, "render": {**TINY["render"], "voxel_size": 0.05}}), out, range(3))


@pytest.mark.slow
def test_sigkill_mid_run_then_rerun_gives_the_uninterrupted_dataset(full_run, tmp_path):
    out, _ = full_run
    cfg_file = tmp_path / "tiny.yaml"
    cfg_file.write_text(yaml.safe_dump(TINY))
    target = tmp_path / "killed"
    cmd = [sys.executable, "-m", "assist3d", "-q", "generate", "--out", str(target), "--num-scenes", "3",
           "--config", str(cfg_file)]
    env = dict(os.environ)
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if (target / "scene_000000" / "meta.json").is_file():
            break
        time.sleep(0.005)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    done = [i for i in range(3) if read_scene_meta(target / scene_name(i)) is not None]
    assert done != [0, 1, 2], "the run finished before it could be killed"
    res = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert dataset_bytes(target) == dataset_bytes(out)
    assert not list(target.rglob(".*.tmp"))


@pytest.mark.slow
def test_generate_show_and_bench_commands(full_run, tmp_path):
    cfg_file = tmp_path / "tiny.yaml"
    cfg_file.write_text(yaml.safe_dump(TINY))
    runner = CliRunner()
    out = tmp_path / "cli"
    res = runner.invoke(app, ["generate", "--out", str(out), "--only", "1", "--config", str(cfg_file), "--ply",
                              "--verify", "--json"])
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout.strip().splitlines()[-1])
    assert summary["generated"] == 1 and summary["failed_checks"] == []
    assert (out / "scene_000001" / "points.ply").is_file()
    assert scene_bytes(out / "scene_000001") == scene_bytes(full_run[0] / "scene_000001")
    from assist3d.export.writer import export_scene_ply

    later = tmp_path / "later"  # the PLY added to a finished scene is the one generation writes
    import shutil

    shutil.copytree(full_run[0] / "scene_000001", later / "scene_000001")
    assert export_scene_ply(later / "scene_000001")
    assert (later / "scene_000001" / "points.ply").read_bytes() == (out / "scene_000001" / "points.ply").read_bytes()
    png = tmp_path / "p.png"
    res = runner.invoke(app, ["show", str(out), "--out", str(png)])
    assert res.exit_code == 0, res.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000
    res = runner.invoke(app, ["show", str(out)])  # not told where: beside the dataset
    assert res.exit_code == 0 and res.stdout.strip() == str(tmp_path / "cli_scene_000001_preview.png")
    assert not list(out.rglob("*.png"))
    bench = run_benchmark(scenes=2, cfg=parse_config(TINY))
    assert set(bench) >= {"scenes", "seconds_per_scene", "stages", "peak_memory_mb"}
    assert set(bench["seconds_per_scene"]) == {"median", "max"}
    assert set(bench["stages"]) == {"select", "layout", "assemble", "render", "fuse", "write"}
    assert bench["scenes"] == 2 and 0 < bench["peak_memory_mb"] < 4000
    # every speed figure names its machine
    assert bench["machine"]["cores"] >= 1 and bench["machine"]["cpu"] and json.dumps(bench["machine"])


def test_a_second_writer_on_the_same_folder_is_refused(full_run):
    import fcntl

    from assist3d.core.errors import DataError

    out, _ = full_run
    with open(out / ".generate.lock", "a+b") as f:
        fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(DataError, match="another"):
            generate_dataset(parse_config(TINY), out, range(3))
        fcntl.flock(f.fileno(), fcntl.LOCK_UN)
    assert generate_dataset(parse_config(TINY), out, range(3)).skipped == [0, 1, 2]


def test_a_failing_scene_is_reported_and_retried_by_the_next_run(full_run, tmp_path, monkeypatch):
    import assist3d.pipeline.scene as pipeline_mod
    from assist3d.core.errors import PlacementError

    real = pipeline_mod.build_layout

    def flaky(catalog, cfg, seed, *, scene_index=0, **kw):
        if scene_index == 1:
            raise PlacementError("room too small for anything (test)")
        return real(catalog, cfg, seed, scene_index=scene_index, **kw)

    monkeypatch.setattr(pipeline_mod, "build_layout", flaky)
    out = tmp_path / "flaky"
    run = generate_dataset(parse_config(TINY), out, range(3))
    assert run.errors == ["scene_000001"]
    assert [m["index"] for m in run.generated] == [0, 2]
    assert [e["id"] for e in json.loads((out / "manifest.json").read_text())["scenes"]] == ["scene_000000",
                                                                                             "scene_000002"]
    monkeypatch.setattr(pipeline_mod, "build_layout", real)
    run = generate_dataset(parse_config(TINY), out, range(3))
    assert run.skipped == [0, 2] and [m["index"] for m in run.generated] == [1] and run.errors == []
    assert dataset_bytes(out) == dataset_bytes(full_run[0])


def test_filled_openings_are_labelled_objects_and_change_nothing_else(full_run, tmp_path):
    out, _ = full_run
    cfg = {**TINY, "room": {**TINY["room"], "fill_openings": True}}
    filled = tmp_path / "filled"
    generate_dataset(parse_config(cfg), filled, range(2), verify=True)
    man = json.loads((filled / "manifest.json").read_text())
    plain_classes = json.loads((out / "manifest.json").read_text())["classes"]
    assert man["classes"][:len(plain_classes)] == plain_classes and {"door", "window"} <= set(man["classes"])
    seen = set()
    for i in range(2):
        sid = scene_name(i)
        assert next(e for e in man["scenes"] if e["id"] == sid)["check"]["ok"]  # ray labels agree with the mesh
        lay = json.loads((filled / sid / "layout.json").read_text())
        ref = json.loads((out / sid / "layout.json").read_text())
        # the objects and their poses are those of the plain run: the fill draws from its own stream
        assert lay["instances"] == ref["instances"]
        openings = lay["room"]["openings"]
        assert [{k: o[k] for k in ("kind", "wall", "offset", "width", "bottom", "top")} for o in openings] == \
            ref["room"]["openings"]
        inst = np.load(filled / sid / "instance.npy")
        seg = np.load(filled / sid / "segment.npy")
        for o in openings:
            pts = inst == o["instance"]
            seen.add(o["kind"])
            if pts.any():
                assert set(seg[pts].tolist()) == {man["classes"].index(o["kind"])}
        assert len({o["instance"] for o in openings} & {x["id"] for x in lay["instances"]}) == 0
    assert "door" in seen


def test_rays_option_picks_the_render(tmp_path):
    """`generate --rays full` renders one ray per pixel (the reference), the default the ray budget,
    `--rays footprint` the sampled render; `bench --rays` the same; anything else is one clear error."""
    cfg_file = tmp_path / "tiny.yaml"
    cfg_file.write_text(yaml.safe_dump(TINY))
    runner = CliRunner()
    metas = {}
    for rays in ("full", None, "footprint"):
        out = tmp_path / str(rays)
        args = ["generate", "--out", str(out), "--only", "0", "--config", str(cfg_file), "--json"]
        res = runner.invoke(app, args + (["--rays", rays] if rays else []))
        assert res.exit_code == 0, res.output
        metas[rays] = json.loads((out / "scene_000000" / "meta.json").read_text())["render"]
    assert "ray_budget" not in metas["full"] and metas[None]["ray_budget"] == "adaptive"
    assert metas[None]["rays_cast"] < metas["full"]["rays"] == metas[None]["rays"]
    assert metas["footprint"]["ray_budget"] == "footprint" and metas["footprint"]["ray_spacing"] == 0.5
    res = runner.invoke(app, ["generate", "--out", str(tmp_path / "x"), "--rays", "half"])
    assert res.exit_code != 0 and "expected full, adaptive or footprint" in res.output
    assert not (tmp_path / "x").exists()
    assert run_benchmark(scenes=1, cfg=parse_config(TINY), rays="full")["settings"]["rays"] == "full"
