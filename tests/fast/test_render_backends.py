"""Ray casting: embree and the numpy reference agree pixel by pixel; depth is along the axis."""

from __future__ import annotations

import math

import numpy as np
import pytest

from assist3d.config import RenderConfig
from assist3d.core.contracts import Camera, Room
from assist3d.core.errors import RenderError
from assist3d.render import make_caster, render_view, vantage_cameras
from assist3d.render.camera import look_pose
from assist3d.render.shapes import box_part, combine_parts, shell_parts, sphere_part

SMALL = dict(width=64, height=48, fx=57.79, fy=57.79)


def small_scene():
    room = Room(((0.0, 0.0), (4.3, 0.0), (4.3, 3.1), (0.0, 3.1)), 2.6, ceiling=True)
    parts = shell_parts(room)
    parts.append(box_part((1.03, 0.81, 0.0), (0.8, 0.5, 0.9), 0.37, (200, 30, 30), 1, 0))
    parts.append(box_part((3.22, 2.13, 0.0), (1.1, 0.6, 1.7), -0.61, (30, 200, 30), 2, 1))
    parts.append(box_part((1.17, 2.41, 0.0), (0.5, 0.5, 0.45), 1.1, (30, 30, 200), 3, 0))
    parts.append(sphere_part((3.37, 0.71, 1.21), 0.29, 2, (220, 220, 20), 4, 2))
    return room, combine_parts(parts)


@pytest.mark.slow
def test_embree_and_numpy_agree_pixel_by_pixel():
    room, scene = small_scene()
    cfg = RenderConfig(**SMALL, views_per_point=6)
    centers = np.array([[2.11, 1.53, 1.3], [0.61, 1.57, 1.1]])
    emb = make_caster("embree", scene.vertices, scene.faces)
    ref = make_caster("numpy", scene.vertices, scene.faces)
    total = same_face = 0
    for cam in vantage_cameras(centers, cfg):
        a = render_view(scene, emb, cam)
        b = render_view(scene, ref, cam)
        hit = a.face >= 0
        assert np.array_equal(hit, b.face >= 0)
        assert hit.all()  # closed room with a ceiling: every ray hits something
        assert np.array_equal(a.instance, b.instance)
        assert np.abs(a.depth - b.depth).max() < 1e-4
        total += hit.size
        same_face += int(np.count_nonzero(a.face == b.face))
        np.testing.assert_array_equal(a.color, b.color)
    assert same_face == total


def test_depth_is_along_the_optical_axis():
    room = Room(((0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)), 6.0, ceiling=True)
    scene = combine_parts(shell_parts(room))
    caster = make_caster("embree", scene.vertices, scene.faces)
    # looking along +x from x = 3: the wall x = 10 is 7 m away at every pixel seeing it
    cam = Camera(64, 48, 57.79, 57.79, 31.5, 23.5, look_pose(np.array([3.0, 5.0, 3.0]), 0.0))
    v = render_view(scene, caster, cam)
    wall = v.instance == -1
    assert wall.all()
    # every pixel's ray lands on the far wall (the view is narrow), so depth is constant
    np.testing.assert_allclose(v.depth, 7.0, atol=1e-4)


def test_pose_axes_follow_opencv_convention():
    pose = look_pose(np.zeros(3), math.pi / 2, 0.0)  # looking along +y
    np.testing.assert_allclose(pose[:3, 2], [0, 1, 0], atol=1e-12)  # forward
    np.testing.assert_allclose(pose[:3, 1], [0, 0, -1], atol=1e-12)  # image down = world down
    np.testing.assert_allclose(np.linalg.det(pose[:3, :3]), 1.0)


def test_unknown_backend_and_budget_are_clear_errors():
    _, scene = small_scene()
    with pytest.raises(RenderError, match="unknown render backend"):
        make_caster("optix", scene.vertices, scene.faces)
    ref = make_caster("numpy", scene.vertices, scene.faces)
    ref._max_pairs = 10  # type: ignore[attr-defined]
    with pytest.raises(RenderError, match="budget"):
        ref.cast(np.zeros((5, 3), np.float32), np.ones((5, 3), np.float32))
