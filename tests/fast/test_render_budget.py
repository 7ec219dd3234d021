"""The adaptive ray budget (render.rays = adaptive): the same pixels, points and labels as the full
render from a fraction of its rays; slender parts are not stepped over; the config key."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import ValidationError

from assist3d.config import RenderConfig
from assist3d.core.contracts import Room
from assist3d.render import make_caster, render_point_cloud, vantage_cameras
from assist3d.render.budget import cast_adaptive, face_planes, lattice, sky_box, slender_parts
from assist3d.render.camera import pixel_directions, rotate_directions
from assist3d.render.fusion import scene_grid
from assist3d.render.shapes import box_part, combine_parts, shell_parts, sphere_part

SMALL = dict(width=160, height=120, fx=144.5, fy=144.5, vantage_points=3, views_per_point=8, vantage_clearance=0.25)


def room_with_bars():
    """An L-shaped room with furniture-sized boxes, a sphere and a row of 2 cm bars (a crib's side)
    standing 0.3 m in front of a wall."""
    room = Room(((0.0, 0.0), (5.0, 0.0), (5.0, 2.0), (3.0, 2.0), (3.0, 4.0), (0.0, 4.0)), 2.5, ceiling=False)
    parts = shell_parts(room)
    parts.append(box_part((1.0, 0.8, 0.0), (0.8, 0.5, 0.9), 0.3, (200, 30, 30), 1, 0))
    parts.append(box_part((4.2, 1.0, 0.0), (0.9, 0.6, 1.8), -0.6, (30, 200, 30), 2, 1))
    parts.append(sphere_part((2.0, 2.0, 0.9), 0.25, 2, (220, 220, 20), 4, 2))
    for k in range(12):
        parts.append(box_part((0.8 + 0.09 * k, 3.7, 0.0), (0.02, 0.02, 1.0), 0.0, (120, 80, 40), 5, 3))
    return room, combine_parts(parts)


@pytest.fixture(scope="module")
def scene():
    return room_with_bars()


def _views(scene, cfg):
    room, mesh = scene
    from assist3d.render import select_vantage_points

    centers = select_vantage_points(mesh, room, cfg, rng=np.random.default_rng(3))
    return vantage_cameras(centers, cfg)


def test_lattice_nests_and_ends_on_the_last_pixel():
    for n in (8, 72, 480, 641):
        for s in (1, 2, 4, 8, 16):
            a, b = lattice(n, s), lattice(n, max(s // 2, 1))
            assert a[0] == 0 and a[-1] == n - 1 and np.all(np.diff(a) > 0) and np.all(np.diff(a) <= s)
            assert np.isin(a, b).all()


def _adaptive_against_full(scene, sky: bool) -> tuple[int, int]:
    """Every view of the small scene cast adaptively (with or without the sky box) against the full
    render: the same pixels; returns (rays cast, pixels)."""
    room, mesh = scene
    cfg = RenderConfig(**SMALL)
    caster = make_caster("embree", mesh.vertices, mesh.faces)
    sky_caster = make_caster("embree", *sky_box(mesh)) if sky else None
    planes = face_planes(mesh, sky=sky)
    cams = _views(scene, cfg)
    c0 = cams[0]
    cam_dirs = pixel_directions(c0.width, c0.height, c0.fx, c0.fy, c0.cx, c0.cy).astype(np.float32)
    cast = pixels = 0
    for cam in cams:
        dirs = rotate_directions(cam_dirs, cam.pose)
        origins = np.zeros_like(dirs)
        origins[:] = cam.pose[:3, 3].astype(np.float32)
        t_ref, f_ref = caster.cast(origins, dirs)
        t, f, n = cast_adaptive(caster, planes, cam, dirs, 8, sky_caster)
        # the same pixels: the same triangle and depth (to rounding), but for the odd pixel where a
        # corner of a box pokes into a tile without touching its corner rays; sky is a miss
        np.testing.assert_array_equal(f >= 0, f_ref >= 0)
        assert f.max() < len(mesh.faces)
        same = f == f_ref
        assert np.count_nonzero(~same) <= 2
        hit = same & (f_ref >= 0)
        np.testing.assert_allclose(t[hit], t_ref[hit], rtol=2e-6)
        assert np.all(np.isinf(t[f < 0]))
        cast += n
        pixels += len(f)
    return cast, pixels


def test_adaptive_views_equal_the_full_views_from_fewer_rays(scene):
    cast, pixels = _adaptive_against_full(scene, sky=False)
    assert cast < 0.6 * pixels  # a plain room: most tiles are flat
    # the room has no ceiling: without the sky box every ray into the open is cast, with it most are not
    cast_sky, _ = _adaptive_against_full(scene, sky=True)
    assert cast_sky < 0.9 * cast


def test_sky_box_encloses_the_scene(scene):
    _, mesh = scene
    box, f = sky_box(mesh)
    assert box.shape == (8, 3) and f.shape == (12, 3) and set(np.unique(f)) == set(range(8))
    np.testing.assert_allclose(box.min(0), mesh.vertices.min(0) - 1.0, atol=1e-5)
    np.testing.assert_allclose(box.max(0), mesh.vertices.max(0) + 1.0, atol=1e-5)
    # its 12 triangles cover the 6 faces: every ray from inside hits the box
    from assist3d.render.raycast import NumpyCaster
    rays = np.random.default_rng(0).normal(size=(200, 3)).astype(np.float32)
    centre = np.repeat(mesh.vertices.mean(0, keepdims=True), 200, 0).astype(np.float32)
    _, hit = NumpyCaster(box, f).cast(centre, rays)
    assert np.all(hit >= 0)
    planes = face_planes(mesh, sky=True)
    assert planes.scene_faces == len(mesh.faces) and len(planes.offset) == len(mesh.faces) + 12
    assert np.all(planes.bar_of_face[len(mesh.faces):] == -1)


def test_slender_parts_are_found_and_keep_their_pixels(scene):
    room, mesh = scene
    bars = slender_parts(mesh)
    # the 12 bars (2 x 2 x 100 cm) are slender; the furniture boxes and the sphere are not
    assert len(bars) == 12
    assert np.allclose(np.sort(np.ptp(bars, axis=1), axis=1)[:, 2], 1.0, atol=1e-3)
    of_face = face_planes(mesh).bar_of_face
    assert set(np.unique(of_face[mesh.face_instance == 5])) == set(range(12))
    assert np.all(of_face[mesh.face_instance != 5] == -1)
    # without them in the budget, a coarse lattice steps over the bars: the test above would fail
    caster = make_caster("embree", mesh.vertices, mesh.faces)
    planes = face_planes(mesh)
    blind = type(planes)(planes.normal, planes.offset, np.zeros((0, 8, 3)), None)
    cfg = RenderConfig(**SMALL)
    cams = _views(scene, cfg)
    c0 = cams[0]
    cam_dirs = pixel_directions(c0.width, c0.height, c0.fx, c0.fy, c0.cx, c0.cy).astype(np.float32)
    lost = kept = 0
    for cam in cams:
        dirs = rotate_directions(cam_dirs, cam.pose)
        origins = np.zeros_like(dirs)
        origins[:] = cam.pose[:3, 3].astype(np.float32)
        _, f_ref = caster.cast(origins, dirs)
        bar_px = mesh.face_instance[np.maximum(f_ref, 0)] == 5
        bar_px &= f_ref >= 0
        _, f_blind, _ = cast_adaptive(caster, blind, cam, dirs, 8)
        _, f_safe, _ = cast_adaptive(caster, planes, cam, dirs, 8)
        lost += int(np.count_nonzero(bar_px & (f_blind != f_ref)))
        kept += int(np.count_nonzero(bar_px & (f_safe == f_ref)))
        assert np.array_equal(f_safe[bar_px], f_ref[bar_px])
    assert kept > 0 and lost > 0


def test_adaptive_cloud_covers_the_full_cloud(scene):
    """Coverage and label agreement on a small scene (docs/generation.md, 'Ray budget')."""
    room, mesh = scene
    full = render_point_cloud(mesh, room, RenderConfig(**SMALL, rays="full"), rng=np.random.default_rng(7))
    fast = render_point_cloud(mesh, room, RenderConfig(**SMALL, rays="adaptive"), rng=np.random.default_rng(7))
    grid = scene_grid(mesh, 0.02)
    kr, kf = grid.keys(full.sample.coord), grid.keys(fast.sample.coord)
    common, ir, jf = np.intersect1d(kr, kf, assume_unique=True, return_indices=True)
    assert len(common) / len(kr) >= 0.99
    assert np.mean(full.sample.instance[ir] == fast.sample.instance[jf]) >= 0.999
    assert set(np.unique(full.sample.instance)) == set(np.unique(fast.sample.instance))
    np.testing.assert_allclose(fast.pixel_counts, full.pixel_counts, rtol=1e-3)
    assert fast.stats["rays_cast"] < full.stats["rays"] and fast.stats["ray_budget"] == "adaptive"
    assert "rays_cast" not in full.stats  # the full render's record is as it was
    # same seed, same cloud
    again = render_point_cloud(mesh, room, RenderConfig(**SMALL, rays="adaptive", threads=1),
                               rng=np.random.default_rng(7))
    np.testing.assert_array_equal(again.sample.coord, fast.sample.coord)
    np.testing.assert_array_equal(again.sample.instance, fast.sample.instance)


def test_ray_tile_is_a_power_of_two():
    assert RenderConfig(rays="adaptive", ray_tile=16).ray_tile == 16
    with pytest.raises(ValidationError, match="power of two"):
        RenderConfig(ray_tile=12)
    with pytest.raises(ValidationError):
        RenderConfig(rays="half")


def test_footprint_samples_the_full_cloud_from_fewer_hits(scene):
    """rays='footprint': nearly every voxel of the full render from a fraction of its rays and hits,
    labels from the rays' own triangles; a coarser spacing keeps fewer; same seed, same cloud."""
    room, mesh = scene
    full = render_point_cloud(mesh, room, RenderConfig(**SMALL, rays="full"), rng=np.random.default_rng(7))
    grid = scene_grid(mesh, 0.02)
    kr = grid.keys(full.sample.coord)
    adaptive = render_point_cloud(mesh, room, RenderConfig(**SMALL, rays="adaptive"), rng=np.random.default_rng(7))
    runs = {}
    for spacing in (0.5, 2.0):
        cfg = RenderConfig(**SMALL, rays="footprint", ray_spacing=spacing)
        fast = render_point_cloud(mesh, room, cfg, rng=np.random.default_rng(7))
        kf = grid.keys(fast.sample.coord)
        common = np.intersect1d(kr, kf, assume_unique=True)
        runs[spacing] = (len(common) / len(kr), fast)
        assert fast.stats["ray_budget"] == "footprint" and fast.stats["ray_spacing"] == spacing
        # every point's label is the triangle its ray hit: the instance of the re-cast point agrees
        assert set(np.unique(fast.sample.instance)) <= set(np.unique(full.sample.instance))
    cover, fast = runs[0.5]
    assert cover >= 0.99
    assert fast.stats["raw_hits"] < 0.9 * adaptive.stats["raw_hits"]  # (coarse 160 x 120 views: few to spare)
    assert fast.stats["rays_cast"] < 1.1 * adaptive.stats["rays_cast"]  # 160 x 120: a flat tile's edges get cast
    # 2 voxels apart is too coarse to fill every voxel, and casts fewer rays still
    assert runs[2.0][0] < cover and runs[2.0][1].stats["rays_cast"] < fast.stats["rays_cast"]
    again = render_point_cloud(mesh, room, RenderConfig(**SMALL, rays="footprint", ray_spacing=0.5, threads=1),
                               rng=np.random.default_rng(7))
    np.testing.assert_array_equal(again.sample.coord, fast.sample.coord)
    np.testing.assert_array_equal(again.sample.instance, fast.sample.instance)


def test_footprint_renders_whole_views_where_they_are_needed(scene):
    """Depth-sensor options see neighbouring pixels: with them footprint renders as adaptive, and says so."""
    room, mesh = scene
    kw = dict(SMALL, edge_dropout=0.05)
    a = render_point_cloud(mesh, room, RenderConfig(**kw, rays="adaptive"), rng=np.random.default_rng(7))
    f = render_point_cloud(mesh, room, RenderConfig(**kw, rays="footprint"), rng=np.random.default_rng(7))
    np.testing.assert_array_equal(a.sample.coord, f.sample.coord)
    assert f.stats["ray_budget"] == "adaptive" and "ray_spacing" not in f.stats
