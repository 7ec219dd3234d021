"""Fusion: one point per voxel, exact labels, determinism, sensor options, the mesh baseline."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.config import RenderConfig
from assist3d.core.contracts import Room
from assist3d.render import build_point_cloud, make_caster, render_point_cloud, verify_labels
from assist3d.render.fusion import scene_grid
from assist3d.render.shapes import box_part, combine_parts, shell_parts, sphere_part

# the reference render (one ray per pixel); the default ray budget is checked against it in test_render_budget.py
SMALL = dict(width=96, height=72, fx=86.7, fy=86.7, vantage_points=3, views_per_point=8, vantage_clearance=0.25,
             rays="full")


def scene_with_hidden_box():
    room = Room(((0.0, 0.0), (5.0, 0.0), (5.0, 2.0), (3.0, 2.0), (3.0, 4.0), (0.0, 4.0)), 2.5, ceiling=False)
    parts = shell_parts(room)
    parts.append(box_part((1.0, 0.8, 0.0), (0.8, 0.5, 0.9), 0.3, (200, 30, 30), 1, 0))
    parts.append(box_part((4.2, 1.0, 0.0), (0.9, 0.6, 1.8), -0.6, (30, 200, 30), 2, 1))
    parts.append(box_part((1.0, 3.2, 0.0), (0.5, 0.5, 0.45), 1.1, (30, 30, 200), 3, 0))
    parts.append(sphere_part((2.0, 2.0, 0.9), 0.25, 2, (220, 220, 20), 4, 2))
    # instance 5 is a box sealed inside instance 6: no ray can reach it
    parts.append(box_part((0.6, 2.0, 0.0), (0.8, 0.8, 0.8), 0.0, (90, 90, 90), 6, 1))
    parts.append(box_part((0.6, 2.0, 0.1), (0.3, 0.3, 0.3), 0.0, (250, 0, 250), 5, 2))
    return room, combine_parts(parts)


@pytest.fixture(scope="module")
def scene():
    return scene_with_hidden_box()


@pytest.fixture(scope="module")
def rendered(scene):
    room, mesh = scene
    return render_point_cloud(mesh, room, RenderConfig(**SMALL), rng=np.random.default_rng(7), scene_id="t")


def test_cloud_contract_and_one_point_per_voxel(scene, rendered):
    room, mesh = scene
    s = rendered.sample
    assert len(s) > 5000
    assert s.coord.dtype == np.float32 and s.color.dtype == np.uint8 and s.normal.dtype == np.float32
    keys = scene_grid(mesh, 0.02).keys(s.coord)
    assert len(np.unique(keys)) == len(keys)
    np.testing.assert_allclose(np.linalg.norm(s.normal, axis=1), 1.0, atol=1e-4)
    lo, hi = mesh.vertices.min(0) - 1e-3, mesh.vertices.max(0) + 1e-3
    assert np.all((s.coord >= lo) & (s.coord <= hi))
    # every normal faces one of the vantage points (oriented towards the camera that saw it)
    to_cam = rendered.centers[None, :, :].astype(np.float32) - s.coord[:, None, :]
    assert np.all(np.einsum("nkj,nj->nk", to_cam, s.normal).max(axis=1) > 0)


def test_labels_are_exact_and_segments_follow_instances(scene, rendered):
    room, mesh = scene
    s = rendered.sample
    caster = make_caster("embree", mesh.vertices, mesh.faces)
    check = verify_labels(mesh, caster, s, rendered.centers, pixel_counts=rendered.pixel_counts)
    assert check.checked == len(s)
    assert check.agreement == 1.0 and check.background_with_instance == 0
    assert check.missing_instances == ()
    assert check.ok()
    assert set(np.unique(s.instance)) == {-1, 1, 2, 3, 4, 6}  # 5 is sealed away
    seg_of = {1: 0, 2: 1, 3: 0, 4: 2, 6: 1, -1: -1}
    assert all(seg_of[i] == g for i, g in zip(s.instance.tolist()[::97], s.segment.tolist()[::97]))


def test_labels_of_the_default_ray_budget_pass_the_check(scene):
    """The default render (render.rays = adaptive) fills flat tiles from their triangle's plane: its
    labels pass the label check (re-cast rays, the generator's --verify) all but a few points."""
    room, mesh = scene
    assert RenderConfig().rays == "adaptive"
    res = render_point_cloud(mesh, room, RenderConfig(**(SMALL | {"rays": "adaptive"})), rng=np.random.default_rng(7),
                             scene_id="t")
    check = verify_labels(mesh, make_caster("embree", mesh.vertices, mesh.faces), res.sample, res.centers,
                          pixel_counts=res.pixel_counts)
    assert check.checked == len(res.sample) and check.ok(min_agreement=0.9995)


def test_verify_catches_wrong_labels(scene, rendered):
    room, mesh = scene
    s = rendered.sample
    wrong = s.instance.copy()
    bg = np.flatnonzero(wrong == -1)[:50]
    wrong[bg] = 1  # background points now claim to be object 1
    from dataclasses import replace

    bad = replace(s, instance=wrong)
    caster = make_caster("embree", mesh.vertices, mesh.faces)
    check = verify_labels(mesh, caster, bad, rendered.centers)
    assert check.background_with_instance == 50
    assert not check.ok()


def test_same_seed_same_bytes_whatever_the_thread_count(scene, rendered):
    room, mesh = scene
    other = render_point_cloud(mesh, room, RenderConfig(**SMALL, threads=1), rng=np.random.default_rng(7))
    for name in ("coord", "color", "normal", "instance", "segment"):
        assert getattr(other.sample, name).tobytes() == getattr(rendered.sample, name).tobytes(), name
    third = render_point_cloud(mesh, room, RenderConfig(**SMALL), rng=np.random.default_rng(8))
    assert third.sample.coord.tobytes() != rendered.sample.coord.tobytes()


@pytest.mark.slow
def test_numpy_backend_gives_the_same_cloud(scene, rendered):
    room, mesh = scene
    small = dict(SMALL, width=48, height=36, fx=43.3, fy=43.3, views_per_point=4)
    a, _ = build_point_cloud(mesh, room, RenderConfig(**small), rng=np.random.default_rng(3))
    b, _ = build_point_cloud(mesh, room, RenderConfig(**small, backend="numpy"), rng=np.random.default_rng(3))
    # the same voxels and points; labels may differ only where a ray ends exactly on the seam of
    # coplanar faces (an object's base on the floor), a true tie
    np.testing.assert_allclose(a.coord, b.coord, atol=1e-4)
    assert np.mean(a.instance == b.instance) > 0.999


def test_nearest_labels_match_ray_labels_away_from_contacts(scene, rendered):
    room, mesh = scene
    res = render_point_cloud(mesh, room, RenderConfig(**SMALL, labels="nearest"), rng=np.random.default_rng(7))
    ray = rendered.sample.instance
    near = res.sample.instance
    assert np.array_equal(res.sample.coord, rendered.sample.coord)
    assert np.mean(near == ray) > 0.97
    obj = ray >= 0
    assert np.all(near[obj] == ray[obj]) or np.mean(near[obj] == ray[obj]) > 0.99
    # the nearest rule leaks labels onto floor points touching objects, never onto far walls
    walls = (ray == -1) & (rendered.sample.coord[:, 2] > 2.0)
    assert np.all(near[walls] == -1)


def test_sensor_options_change_the_cloud_deterministically(scene, rendered):
    room, mesh = scene
    base = rendered.sample

    def run(**kw):
        return render_point_cloud(mesh, room, RenderConfig(**SMALL, **kw), rng=np.random.default_rng(7)).sample

    far = run(max_range=2.0)
    assert len(far) < len(base)
    noisy = run(depth_noise=0.01)
    assert np.array_equal(noisy.coord, run(depth_noise=0.01).coord)
    assert not np.array_equal(noisy.coord, base.coord)
    edges = run(edge_dropout=0.1)
    assert len(edges) < len(base)
    graze = run(grazing_dropout_deg=60.0)
    assert len(graze) < len(base)
    jit = run(color_jitter=0.2)
    assert np.array_equal(jit.coord, base.coord) and not np.array_equal(jit.color, base.color)
    flat = run(shading=False)
    assert np.array_equal(np.unique(flat.color, axis=0).shape[0] <= 8, True)


def test_mesh_baseline_sees_hidden_surfaces_at_matching_density(scene, rendered):
    room, mesh = scene
    res = render_point_cloud(mesh, room, RenderConfig(**SMALL, point_source="mesh"), rng=np.random.default_rng(7))
    s = res.sample
    assert len(s) == len(rendered.sample)
    assert 5 in set(s.instance.tolist())  # no occlusion: the sealed box is sampled
    keys = scene_grid(mesh, 0.02).keys(s.coord)
    assert len(np.unique(keys)) == len(keys)
    # every sample lies on its triangle's plane
    inst5 = s.coord[s.instance == 5]
    assert inst5[:, 2].min() >= 0.1 - 1e-4 and inst5[:, 2].max() <= 0.4 + 1e-4


def test_one_per_voxel_pickers_keep_exactly_one_row_per_key_and_vary_with_salt():
    from assist3d.render.voxel import pick_one_per_voxel, pick_one_per_voxel_scan

    rng = np.random.default_rng(0)
    keys = np.repeat(rng.integers(0, 500, 300), rng.integers(1, 9, 300))  # runs, with repeats far apart
    for pick in (pick_one_per_voxel, pick_one_per_voxel_scan):
        a = pick(keys, 12345)
        assert np.array_equal(np.sort(keys[a]), np.unique(keys))
        assert np.all(np.diff(keys[a]) > 0)  # sorted by voxel
        assert np.array_equal(a, pick(keys, 12345))
        assert not np.array_equal(a, pick(keys, 999))
    # within a voxel the choice is spread over its rows, not always the first one
    keys = np.zeros(64, np.int64)
    chosen = {int(pick_one_per_voxel(keys, s)[0]) for s in range(1, 200)}
    assert len(chosen) > 20


def test_empty_room_gives_an_all_background_cloud():
    room = Room(((0.0, 0.0), (3.0, 0.0), (3.0, 3.0), (0.0, 3.0)), 2.5, ceiling=False)
    mesh = combine_parts(shell_parts(room))
    res = render_point_cloud(mesh, room, RenderConfig(**SMALL), rng=np.random.default_rng(0))
    assert len(res.sample) > 1000 and len(res.pixel_counts) == 0
    assert np.all(res.sample.instance == -1) and np.all(res.sample.segment == -1)
    # the floor is seen, and every point lies on the floor or a wall
    c = res.sample.coord
    on_surface = (np.abs(c[:, 2]) < 1e-4) | (np.min(np.abs(np.c_[c[:, 0], c[:, 0] - 3, c[:, 1], c[:, 1] - 3]), axis=1) < 1e-4)
    assert on_surface.all() and np.any(np.abs(c[:, 2]) < 1e-4)
