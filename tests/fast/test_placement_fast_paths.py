"""The layout stage's fast paths give what the plain computations give (issue 52: layouts must not
change): window and rectangle sums from summed-area tables against brute-force counts, and the
height pre-filter of boxes_collide against testing every box."""

from __future__ import annotations

import numpy as np

from assist3d.core.geometry import boxes_collide, footprints_overlap, z_overlap
from assist3d.placement.floor import _sums
from assist3d.placement.surface import _sat, _window_sums


def test_window_sums_count_the_cells_of_each_clamped_window():
    rng = np.random.default_rng(0)
    for _ in range(60):
        ny, nx = (int(v) for v in rng.integers(1, 25, 2))
        ex, ey = (int(v) for v in rng.integers(0, 30, 2))
        mask = rng.random((ny, nx)) > 0.4
        got = _window_sums(_sat(mask), ex, ey)
        want = np.array([[mask[max(j - ey, 0):j + ey + 1, max(i - ex, 0):i + ex + 1].sum() for i in range(nx)]
                         for j in range(ny)])
        np.testing.assert_array_equal(got, want)


def test_rectangle_sums_of_every_row_range_with_every_column_range():
    rng = np.random.default_rng(1)
    for _ in range(40):
        ny, nx = (int(v) for v in rng.integers(1, 30, 2))
        mask = rng.random((ny, nx)) > 0.5
        sat = _sat(mask)
        i0 = rng.integers(-2, nx + 1, 7)
        i1 = np.maximum(i0, 0) + rng.integers(0, 12, 7)
        j0 = rng.integers(-2, ny + 1, 5)
        j1 = np.maximum(j0, 0) + rng.integers(0, 12, 5)
        got = _sums(sat, i0, i1, j0, j1)
        want = np.array([[mask[max(a, 0):min(b, ny), max(c, 0):min(d, nx)].sum() for c, d in zip(i0, i1)]
                         for a, b in zip(j0, j1)])
        np.testing.assert_array_equal(got, want)


def test_boxes_collide_with_its_height_prefilter_equals_testing_every_box():
    rng = np.random.default_rng(2)
    for _ in range(30):
        m, n = (int(v) for v in rng.integers(1, 12, 2))
        z0 = rng.uniform(0, 2, m)
        boxes = {"x": rng.uniform(0, 3, m), "y": rng.uniform(0, 3, m), "yaw": rng.uniform(0, 6.3, m),
                 "hw": rng.uniform(0.05, 0.6, m), "hd": rng.uniform(0.05, 0.6, m), "z0": z0,
                 "z1": z0 + rng.uniform(0.01, 1, m)}
        boxes["hx"], boxes["hy"] = boxes["hw"] + boxes["hd"], boxes["hw"] + boxes["hd"]  # loose broad phase
        cx, cy, cyaw = rng.uniform(0, 3, n), rng.uniform(0, 3, n), rng.uniform(0, 6.3, n)
        cz0 = np.full(n, rng.uniform(0, 2))
        cz1 = cz0 + 0.3
        want = (footprints_overlap(cx, cy, cyaw, 0.2, 0.3, boxes, 0.01) & z_overlap(cz0, cz1, boxes)).any(1)
        np.testing.assert_array_equal(boxes_collide(cx, cy, cyaw, 0.2, 0.3, cz0, cz1, boxes, 0.01), want)
