"""The dataset writer: Pointcept layout loadable by plain numpy, marker last, PLY, manifest."""

from __future__ import annotations

import json

import numpy as np
import pytest

from assist3d.core.contracts import PointSample, Room, SceneLayout
from assist3d.core.errors import DataError
from assist3d.export import Manifest, load_scene_arrays, read_scene_meta, write_scene
from assist3d.export.ply import instance_colors


def sample(n=500, seed=0) -> PointSample:
    rng = np.random.default_rng(seed)
    inst = rng.integers(-1, 4, n).astype(np.int32)
    return PointSample("s", rng.random((n, 3), dtype=np.float32), rng.integers(0, 255, (n, 3), dtype=np.uint8),
                       rng.random((n, 3), dtype=np.float32), inst, np.where(inst >= 0, inst % 2, -1).astype(np.int32),
                       np.ones(n, bool))


LAYOUT = SceneLayout(Room(((0.0, 0.0), (3.0, 0.0), (3.0, 3.0), (0.0, 3.0)), 2.5), (), (), 5, 0.1)


def test_scene_folder_loads_like_pointcept_and_marker_lists_every_file(tmp_path):
    s = sample()
    meta = write_scene(tmp_path / "scene_000000", s, LAYOUT, {"id": "scene_000000", "seed": 5,
                                                              "seconds": {"render": 1.0}}, ply=True)
    d = tmp_path / "scene_000000"
    # what Pointcept's DefaultDataset does: np.load each array by name
    data = {k: np.load(d / f"{k}.npy") for k in ("coord", "color", "normal", "instance", "segment")}
    assert data["coord"].dtype == np.float32 and data["coord"].shape == (500, 3)
    assert data["color"].dtype == np.uint8 and data["color"].shape == (500, 3)
    assert data["normal"].dtype == np.float32 and data["normal"].shape == (500, 3)
    assert data["instance"].dtype == np.int32 and data["instance"].shape == (500,)
    assert data["segment"].dtype == np.int32 and data["segment"].shape == (500,)
    assert np.array_equal(data["instance"], s.instance)
    assert set(meta["files"]) == {"coord.npy", "color.npy", "normal.npy", "instance.npy", "segment.npy",
                                  "segment20.npy", "segment200.npy", "layout.json", "points.ply"}
    assert meta["seconds"]["write"] >= 0 and meta["seconds"]["render"] == 1.0
    assert read_scene_meta(d)["seed"] == 5
    assert SceneLayout.from_json(json.loads((d / "layout.json").read_text())).seed == 5
    assert load_scene_arrays(d)["segment"].dtype == np.int32
    assert not list(d.glob(".*tmp"))  # no temporary files left behind
    import os
    import stat

    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE((d / "coord.npy").stat().st_mode) == 0o666 & ~umask  # not mkstemp's 0600


def test_incomplete_or_corrupted_scene_is_not_complete(tmp_path):
    d = tmp_path / "scene_000001"
    write_scene(d, sample(), LAYOUT, {"id": "scene_000001", "seed": 5})
    assert read_scene_meta(d) is not None
    raw = bytearray((d / "instance.npy").read_bytes())
    raw[-1] ^= 0xFF
    (d / "instance.npy").write_bytes(bytes(raw))
    assert read_scene_meta(d) is None  # hash mismatch
    assert read_scene_meta(d, check_files=False) is not None
    (d / "meta.json").unlink()
    assert read_scene_meta(d) is None
    (d / "coord.npy").write_bytes(b"\x93NUMPY garbage")
    with pytest.raises(DataError, match="coord.npy"):
        load_scene_arrays(d)


def test_ply_is_binary_with_instance_colours(tmp_path):
    s = sample(50)
    write_scene(tmp_path / "x", s, LAYOUT, {"id": "x"}, ply=True)
    raw = (tmp_path / "x" / "points.ply").read_bytes()
    head, body = raw.split(b"end_header\n", 1)
    assert b"element vertex 50" in head and b"binary_little_endian" in head
    rec = np.frombuffer(body, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("r", "u1"), ("g", "u1"), ("b", "u1"),
                                     ("instance", "<i4"), ("segment", "<i4")])
    assert np.array_equal(rec["instance"], s.instance)
    cols = instance_colors(s.instance)
    assert np.array_equal(rec["r"], cols[:, 0])
    assert np.all(cols[s.instance == -1] == 170)
    # distinct instances get distinct colours
    assert len({tuple(c) for c in instance_colors(np.arange(40))}) == 40


def test_manifest_refuses_to_mix_settings(tmp_path):
    m = Manifest(tmp_path, {"render": {"voxel_size": 0.02, "threads": 2}}, 0, ("chair",), "proc")
    m.add({"id": "scene_000000", "index": 0, "seed": 1, "instances": 3, "points": 10, "seconds": {"write": 0.1}})
    m.write()
    data = json.loads((tmp_path / "manifest.json").read_text())
    assert data["scenes"][0]["id"] == "scene_000000" and data["classes"] == ["chair"]
    assert {"assist3d", "numpy", "trimesh", "embreex"} <= set(data["versions"])
    Manifest(tmp_path, {"render": {"voxel_size": 0.02, "threads": 1}}, 0, ("chair",), "proc").check_compatible()
    with pytest.raises(DataError, match="config.render"):
        Manifest(tmp_path, {"render": {"voxel_size": 0.05}}, 0, ("chair",), "proc").check_compatible()
    with pytest.raises(DataError, match="seed"):
        Manifest(tmp_path, {"render": {"voxel_size": 0.02}}, 1, ("chair",), "proc").check_compatible()


def test_manifest_of_an_older_version_stays_resumable(tmp_path):
    """A dataset written before an option existed was made with that option's default: resuming it
    with the default is allowed, with another value it is refused."""
    from assist3d.config import GenerateConfig, config_to_dict

    cfg = config_to_dict(GenerateConfig())
    old = json.loads(json.dumps(cfg))
    del old["render"]["tsdf_voxel"], old["render"]["point_source"]  # options a previous version lacked
    Manifest(tmp_path, old, 0, ("chair",), "proc").write()
    Manifest(tmp_path, cfg, 0, ("chair",), "proc").check_compatible()
    cfg["render"]["point_source"] = "tsdf"
    with pytest.raises(DataError, match="config.render"):
        Manifest(tmp_path, cfg, 0, ("chair",), "proc").check_compatible()


def test_manifest_from_before_the_ray_budget_resumes_only_with_the_full_render(tmp_path):
    """render.rays became 'adaptive' by default: a dataset whose config lacks the key was rendered
    with every ray, so resuming it with today's default would mix two renders and is refused."""
    from assist3d.config import GenerateConfig, config_to_dict

    cfg = config_to_dict(GenerateConfig())
    assert cfg["render"]["rays"] == "adaptive"
    old = json.loads(json.dumps(cfg))
    del old["render"]["rays"], old["render"]["ray_tile"]
    Manifest(tmp_path, old, 0, ("chair",), "proc").write()
    with pytest.raises(DataError, match="config.render"):
        Manifest(tmp_path, cfg, 0, ("chair",), "proc").check_compatible()
    cfg["render"]["rays"] = "full"
    Manifest(tmp_path, cfg, 0, ("chair",), "proc").check_compatible()
