"""point_source="tsdf": TSDF fusion + marching cubes gives ScanNet-like clouds with exact labels."""

from __future__ import annotations

import importlib.util
import sys

import numpy as np
import pytest
from pydantic import ValidationError

from assist3d.config import RenderConfig, parse_config
from assist3d.core.contracts import Room
from assist3d.core.errors import ConfigError
from assist3d.render import render_point_cloud
from assist3d.render.fusion import scene_grid
from assist3d.render.shapes import box_part, combine_parts, shell_parts

needs_skimage = pytest.mark.skipif(importlib.util.find_spec("skimage") is None,
                                   reason="scikit-image (the [sim] extra) is not installed")

# a ScanNet-like field of view at 1/5 of the resolution; every pixel integrated (tiny images)
TINY = dict(width=128, height=96, fx=115.6, fy=115.6, vantage_points=3, views_per_point=8, vantage_clearance=0.25,
            tsdf_stride=1, point_source="tsdf")
CUBE = ((1.5, 1.5, 0.0), (0.6, 0.6, 0.6), 0.3)  # base centre, size, yaw


def box_distance(p: np.ndarray, base: tuple, size: tuple, yaw: float) -> np.ndarray:
    """Signed distance (negative inside) of points (N, 3) to a box made by ``box_part``."""
    q = p - np.array([base[0], base[1], base[2] + size[2] / 2])
    c, s = np.cos(yaw), np.sin(yaw)
    local = q @ np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]]).T
    d = np.abs(local) - np.asarray(size) / 2
    return np.linalg.norm(np.maximum(d, 0), axis=1) + np.minimum(d.max(axis=1), 0)


def shell_distance(p: np.ndarray) -> np.ndarray:
    """Distance of points (N, 3) to the floor and walls of the 3 x 3 m room."""
    return np.min(np.abs(np.c_[p[:, 0], p[:, 0] - 3, p[:, 1], p[:, 1] - 3, p[:, 2]]), axis=1)


@pytest.fixture(scope="module")
def scene():
    room = Room(((0.0, 0.0), (3.0, 0.0), (3.0, 3.0), (0.0, 3.0)), 2.5, ceiling=False)
    parts = shell_parts(room)
    parts.append(box_part(*CUBE, (200, 30, 30), 0, 0))
    parts.append(box_part((1.5, 1.5, 0.1), (0.3, 0.3, 0.3), 0.0, (20, 30, 230), 1, 1))  # sealed inside the cube
    return room, combine_parts(parts)


@pytest.fixture(scope="module")
def result(scene):
    pytest.importorskip("skimage.measure")
    room, mesh = scene
    return render_point_cloud(mesh, room, RenderConfig(**TINY), rng=np.random.default_rng(0), scene_id="t")


@pytest.mark.slow
def test_points_lie_on_the_true_surfaces(scene, result):
    room, mesh = scene
    s, voxel = result.sample, RenderConfig().tsdf_voxel
    assert len(s) > 20000
    c = s.coord.astype(np.float64)
    dist = np.minimum(shell_distance(c), np.abs(box_distance(c, *CUBE)))
    assert dist.max() <= 1.5 * voxel + 1e-4  # the far-from-hits rule, hits being exact
    assert np.percentile(dist, 99) < voxel and dist.mean() < 0.2 * voxel
    # one point per voxel_size voxel, contract dtypes, unit normals facing a vantage point
    keys = scene_grid(mesh, 0.02).keys(s.coord)
    assert len(np.unique(keys)) == len(keys)
    assert s.coord.dtype == np.float32 and s.color.dtype == np.uint8 and s.instance.dtype == np.int32
    np.testing.assert_allclose(np.linalg.norm(s.normal, axis=1), 1.0, atol=1e-4)
    to_cam = result.centers[None, :, :].astype(np.float32) - s.coord[:, None, :]
    assert np.all(np.einsum("nkj,nj->nk", to_cam, s.normal).max(axis=1) > 0)


def test_labels_come_from_the_nearest_ray_hit(scene, result):
    s = result.sample
    c = s.coord.astype(np.float64)
    d_cube = box_distance(c, *CUBE)
    on_cube = (np.abs(d_cube) < 0.01) & (c[:, 2] > 0.04)  # away from the floor contact
    assert on_cube.sum() > 500 and np.all(s.instance[on_cube] == 0) and np.all(s.segment[on_cube] == 0)
    away = d_cube > 0.05
    assert np.all(s.instance[away] == -1) and np.all(s.segment[away] == -1)
    assert set(np.unique(s.instance).tolist()) == {-1, 0}


def test_unseen_surfaces_give_no_points(scene, result):
    c = result.sample.coord.astype(np.float64)
    voxel = RenderConfig().tsdf_voxel
    assert 1 not in set(result.sample.instance.tolist())  # the sealed box
    assert not np.any(box_distance(c, *CUBE) < -1.5 * voxel)  # nothing inside the cube
    assert not np.any(c[:, 2] < -voxel)  # nothing under the floor or the cube's base
    assert not np.any((c[:, :2] < -voxel) | (c[:, :2] > 3 + voxel))  # nor behind the walls


def test_stats_name_the_source_and_the_mesh(result):
    st = result.stats
    assert st["point_source"] == "tsdf" and st["points"] == len(result.sample)
    assert st["raw_hits"] > st["mesh_vertices"] > st["points"] > 0 and st["mesh_faces"] > st["mesh_vertices"]
    assert st["mesh_pieces"] >= 1 and st["far_from_hits_dropped"] >= 0


@pytest.mark.slow
def test_same_seed_same_bytes_whatever_the_thread_count(scene, result):
    room, mesh = scene
    again = render_point_cloud(mesh, room, RenderConfig(**TINY), rng=np.random.default_rng(0))
    serial = render_point_cloud(mesh, room, RenderConfig(**TINY, threads=1), rng=np.random.default_rng(0))
    for other in (again, serial):
        for name in ("coord", "color", "normal", "instance", "segment"):
            assert getattr(other.sample, name).tobytes() == getattr(result.sample, name).tobytes(), name
    assert serial.stats == result.stats


def test_slabbed_extraction_matches_one_slab(scene, result, monkeypatch):
    import assist3d.render.tsdf as tsdf

    room, mesh = scene
    monkeypatch.setattr(tsdf, "SLAB_VOXELS", 20_000)  # dozens of slabs instead of one
    sliced = render_point_cloud(mesh, room, RenderConfig(**TINY), rng=np.random.default_rng(0))
    assert sliced.stats == result.stats
    np.testing.assert_allclose(sliced.sample.coord, result.sample.coord, atol=1e-5)
    assert np.array_equal(sliced.sample.instance, result.sample.instance)


@needs_skimage
@pytest.mark.slow
def test_depth_noise_is_integrated_deterministically(scene):
    room, mesh = scene
    cfg = RenderConfig(**dict(TINY, width=96, height=72, fx=86.7, fy=86.7), depth_noise=0.003)
    a = render_point_cloud(mesh, room, cfg, rng=np.random.default_rng(1)).sample
    b = render_point_cloud(mesh, room, cfg, rng=np.random.default_rng(1)).sample
    assert a.coord.tobytes() == b.coord.tobytes()
    c = a.coord.astype(np.float64)
    dist = np.minimum(shell_distance(c), np.abs(box_distance(c, *CUBE)))
    assert np.median(dist) < 0.01  # averaged along the normal


def test_missing_scikit_image_is_a_clear_config_error(scene, monkeypatch):
    room, mesh = scene
    monkeypatch.setitem(sys.modules, "skimage", None)
    monkeypatch.setitem(sys.modules, "skimage.measure", None)
    with pytest.raises(ConfigError) as err:
        render_point_cloud(mesh, room, RenderConfig(**TINY), rng=np.random.default_rng(0))
    msg = str(err.value)
    assert "pip install 'assist3d[sim]'" in msg and "\n" not in msg
    # the other sources do not need it
    render_point_cloud(mesh, room, RenderConfig(**dict(TINY, point_source="render")), rng=np.random.default_rng(0))


@pytest.mark.parametrize("bad", [dict(tsdf_voxel=0.0), dict(tsdf_voxel=-0.01), dict(tsdf_stride=0),
                                 dict(tsdf_trunc=0.0), dict(tsdf_trunc=0.01), dict(tsdf_trunc_per_m=-0.1),
                                 dict(tsdf_max_depth=0.0), dict(tsdf_min_piece_m2=-1.0),
                                 dict(point_source="scan")])
def test_config_rejects_nonsense(bad):
    with pytest.raises(ValidationError):
        RenderConfig(**bad)
    with pytest.raises(ConfigError):
        parse_config({"render": bad})


def test_config_defaults_follow_scannet_where_cheap():
    cfg = RenderConfig()
    assert cfg.point_source == "render"
    assert (cfg.tsdf_voxel, cfg.tsdf_trunc, cfg.tsdf_trunc_per_m, cfg.tsdf_max_depth, cfg.tsdf_stride) == (
        0.02, 0.06, 0.02, 10.0, 2)
