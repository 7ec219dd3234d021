"""Hybrid inference: superpoints, snapping, mask NMS, and the hybrid segmentation of `assist3d segment`."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from assist3d.data import open_dataset  # noqa: E402
from assist3d.bench.evaluation.ap import match_scene, summarize  # noqa: E402
from assist3d.learn.engine.toy import make_toy_scene  # noqa: E402
from assist3d.learn.segmenter.checkpoint import load_segmenter  # noqa: E402
from assist3d.learn.segmenter.cluster import mask_nms  # noqa: E402
from assist3d.learn.segmenter.config import ClusterConfig, parse_segmenter_config  # noqa: E402
from assist3d.learn.segmenter.features import voxelize  # noqa: E402
from assist3d.learn.segmenter.geometric import segment_geometric, structural_points  # noqa: E402
from assist3d.learn.segmenter.hybrid import (  # noqa: E402
    HybridConfig,
    combine,
    labels_from_masks,
    segment_hybrid,
)
from assist3d.learn.segmenter.infer import instances  # noqa: E402
from assist3d.learn.segmenter.model import Segmenter  # noqa: E402
from assist3d.learn.segmenter.superpoints import (  # noqa: E402
    SuperpointConfig, _graph_segments, _merge_segments, snap_masks, superpoints)

TINY_NET = {"net": {"voxel_size": 0.1, "stem_channels": 8, "enc_channels": [8, 16, 16, 24],
                    "dec_channels": [24, 16, 16, 16]}}


@pytest.fixture(scope="module")
def room():
    return make_toy_scene("toy", rng=np.random.default_rng(4), num_objects=4, room_m=4.0, density_per_m2=3000)


@pytest.fixture(scope="module")
def room_superpoints(room):
    return superpoints(room.coord)


@pytest.mark.slow
def test_superpoints_do_not_cross_object_boundaries(room, room_superpoints):
    seg = room_superpoints
    assert seg.shape == (len(room.coord),) and seg.min() == 0
    n_seg = seg.max() + 1
    assert 4 < n_seg < len(room.coord) // 20
    # every superpoint lies on one object or on the structure (box faces meet the floor at a crease)
    impure = 0
    for s in range(n_seg):
        inst = room.instance[seg == s]
        impure += len(inst) - np.bincount(inst + 1).max()
    assert impure / len(seg) < 0.01, impure
    assert np.array_equal(superpoints(room.coord), seg)  # deterministic


def _plain_merge(n, a, b, w, threshold, min_size):
    """Felzenszwalb-Huttenlocher as the paper states it, every edge through both passes: the reference
    for the shortcuts of the package's version."""
    order = np.argsort(w, kind="stable")
    parent, size, limit = list(range(n)), [1] * n, [threshold] * n

    def find(x):
        while parent[x] != x:
            x = parent[x]
        return x

    for e in order:
        u, v = find(a[e]), find(b[e])
        if u != v and w[e] <= limit[u] and w[e] <= limit[v]:
            if size[u] < size[v]:
                u, v = v, u
            parent[v] = u
            size[u] += size[v]
            limit[u] = w[e] + threshold / size[u]
    for e in order:
        u, v = find(a[e]), find(b[e])
        if u != v and (size[u] < min_size or size[v] < min_size):
            if size[u] < size[v]:
                u, v = v, u
            parent[v] = u
            size[u] += size[v]
    return np.unique([find(x) for x in range(n)], return_inverse=True)[1]


def test_segment_merging_equals_the_plain_algorithm():
    # a merge raises a segment's limit above the threshold, so a heavier edge can still merge later
    a, b, w = np.array([0, 2, 1]), np.array([1, 3, 2]), np.array([0.009, 0.009, 0.012])
    assert np.array_equal(_merge_segments(4, a, b, w, 0.01, 1), [0, 0, 0, 0])
    rng = np.random.default_rng(0)
    for n, m, min_size in ((60, 150, 1), (300, 900, 5), (500, 1500, 20)):
        a, b = rng.integers(0, n, m), rng.integers(0, n, m)
        w = np.round(rng.uniform(0.0, 0.05, m), 3)  # rounded: ties between weights too
        got = _merge_segments(n, a, b, w, 0.01, min_size)
        assert np.array_equal(got, _plain_merge(n, a, b, w, 0.01, min_size))


def test_superpoints_of_points_too_far_apart_for_any_edge_are_single_points():
    seg = superpoints(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], np.float32))
    assert sorted(seg.tolist()) == [0, 1, 2, 3, 4]


@pytest.mark.slow
def test_graph_segments_of_a_noisy_room_equal_the_plain_algorithm(room):
    from scipy.spatial import cKDTree

    from assist3d.learn.segmenter.features import neighbourhood_scatter

    cfg = SuperpointConfig()
    # 1 cm of noise spreads the edge weights (a clean toy room has only parallel or square normals)
    coord = room.coord[::3] + np.random.default_rng(0).normal(0.0, 0.01, (len(room.coord[::3]), 3))
    xyz = voxelize(coord, cfg.voxel_size).centres.astype(np.float64)
    tree = cKDTree(xyz)
    nrm = np.linalg.eigh(neighbourhood_scatter(xyz, cfg.k_normal, tree))[1][:, :, 0]
    dist, nn = tree.query(xyz, cfg.k_graph + 1, distance_upper_bound=cfg.max_edge)
    edges = sorted({(min(i, int(j)), max(i, int(j))) for i in range(len(xyz))
                    for j, d in zip(nn[i, 1:], dist[i, 1:]) if np.isfinite(d)})
    a, b = np.array(edges).T
    w = 1.0 - np.abs(np.einsum("ij,ij->i", nrm[a], nrm[b]))
    want = _plain_merge(len(xyz), a, b, w, cfg.threshold, cfg.min_size)
    assert np.array_equal(_graph_segments(xyz, cfg), want)


def test_snapping_restores_a_ragged_mask_and_keeps_one_that_covers_no_segment(room, room_superpoints):
    rng = np.random.default_rng(0)
    box = room.instance == 0
    ragged = box & (rng.random(len(box)) < 0.7)  # 30 % of the object's points missing
    ragged |= (room.instance == -1) & (rng.random(len(box)) < 0.01)  # and a sprinkle of floor and wall points
    snapped = snap_masks(ragged[None], room_superpoints)[0]
    iou = (snapped & box).sum() / (snapped | box).sum()
    assert iou > 0.95 > (ragged & box).sum() / (ragged | box).sum()
    few = np.zeros(len(box), bool)
    few[np.flatnonzero(box)[:3]] = True  # less than half of any superpoint: kept as it is
    assert np.array_equal(snap_masks(few[None], room_superpoints)[0], few)
    assert snap_masks(np.zeros((0, len(box)), bool), room_superpoints).shape == (0, len(box))


def test_mask_nms_drops_the_lower_scored_duplicate_and_labels_take_the_best_mask():
    a = np.zeros(10, bool)
    a[:6] = True
    b = a.copy()
    b[6] = True  # IoU 6/7 with a
    c = np.zeros(10, bool)
    c[4:9] = True  # IoU 2/9 with a: kept
    masks = np.stack([a, b, c])
    keep = mask_nms(masks, np.array([0.5, 0.9, 0.3]), 0.5)
    assert keep.tolist() == [1, 2]
    labels = labels_from_masks(masks[keep])
    assert labels.tolist() == [0, 0, 0, 0, 0, 0, 0, 1, 1, -1]


def test_fallback_proposals_split_touching_objects_below_the_first_proposals():
    # two 30 cm blocks of 5 cm voxels; the offsets pull each block 20 % towards its centre (4 cm
    # between neighbours) and block 1 towards block 0 until their shifted voxels are 6 cm apart:
    # linked at 7 cm (one merged proposal), apart at the 5 cm fallback radius
    cells = np.stack(np.meshgrid(np.arange(6), np.arange(6), np.arange(6), indexing="ij"), -1).reshape(-1, 3)
    coord = np.concatenate([cells, cells + [7, 0, 0]]) * 0.05 + 0.025
    truth = np.repeat([0, 1], len(cells))
    vox = voxelize(coord, 0.05)
    fg = np.full(len(vox), 0.9, np.float32)
    truth_vox = np.empty(len(vox), np.int64)
    truth_vox[vox.inverse] = truth  # one point per voxel
    centre = np.stack([vox.centres[truth_vox == k].mean(0) for k in (0, 1)])[truth_vox]
    offset = 0.2 * (centre - vox.centres)
    offset[truth_vox == 1, 0] -= 0.09
    cluster = ClusterConfig()
    learned = instances(vox, fg, offset, cluster)
    none = np.zeros((0, len(coord)), bool)
    own = np.arange(len(coord))  # every point its own superpoint: snapping keeps masks as they are
    first = combine(learned, vox, fg, offset, cluster, none, own, hybrid=HybridConfig(fallback_radius=None))
    both = combine(learned, vox, fg, offset, cluster, none, own)
    assert len(first.masks) == 1 and first.masks[0].all()  # the merge
    # the first recipe's masks come first, in the same order, with their scores mapped monotonically
    assert np.array_equal(both.masks[: len(first.masks)], first.masks)
    assert np.allclose(both.scores[: len(first.scores)], (1 + first.scores) / 2)
    assert (both.scores[len(first.scores):] < both.scores[len(first.scores) - 1]).all()
    assert sorted(m.sum() for m in both.masks[1:]) == [len(cells), len(cells)]
    assert {int(truth[m][0]) for m in both.masks[1:]} == {0, 1} and all(len(set(truth[m])) == 1 for m in both.masks[1:])
    m = [summarize([match_scene(truth, s.masks, s.scores)]) for s in (first, both)]
    assert (m[0]["AR50"], m[1]["AR50"]) == (0.0, 1.0)
    assert m[0]["AP50"] == 0.0 < m[1]["AP50"]  # 1/3: the merge, a false positive, still ranks first


@pytest.mark.slow
def test_geometric_with_given_planes_equals_finding_them_and_checks_their_shape(room):
    on_plane = structural_points(room.coord)
    assert on_plane.shape == (len(room.coord),) and 0 < on_plane.mean() < 1
    a, b = segment_geometric(room.coord), segment_geometric(room.coord, on_plane=on_plane)
    assert np.array_equal(a.masks, b.masks) and np.array_equal(a.scores, b.scores)
    with pytest.raises(ValueError, match="on_plane has shape"):
        segment_geometric(room.coord, on_plane=on_plane[:-1])


@pytest.mark.slow
def test_hybrid_on_a_toy_room_returns_ranked_consistent_masks_and_finds_the_boxes(room):
    cfg = parse_segmenter_config(TINY_NET)
    torch.manual_seed(0)
    model = Segmenter(cfg.net)  # untrained: the geometric components carry the result
    seg = segment_hybrid(model, cfg, room.coord, room.color)
    assert seg.masks.dtype == bool and seg.masks.shape == (len(seg.scores), len(room.coord))
    assert (np.diff(seg.scores) <= 0).all()
    held = seg.labels >= 0
    assert seg.masks[seg.labels[held], np.flatnonzero(held)].all() and not seg.masks[:, ~held].any()
    m = summarize([match_scene(room.instance, seg.masks, seg.scores, valid=room.valid)])
    assert m["AR"] > 0.7, m.summary  # every box is among the proposals
    first = segment_hybrid(model, cfg, room.coord, room.color, hybrid=HybridConfig(fallback_radius=None))
    assert (np.diff(first.scores) <= 0).all()
    assert summarize([match_scene(room.instance, first.masks, first.scores, valid=room.valid)])["AR"] > 0.7


@pytest.mark.slow
def test_shipped_model_hybrid_beats_the_reference_on_the_real_scan(real_scan_path, one_thread):
    """Hybrid inference (segment --method hybrid) keeps its time bound and stays ahead of the geometric
    reference it builds on. It no longer beats the network alone here: with the 2,000-step model the
    network alone became segment's default (docs/results.md)."""
    import time

    from assist3d.learn.segmenter.infer import segment_points
    from assist3d.learn.segmenter.shipped import shipped_model_path

    loaded = load_segmenter(shipped_model_path())
    s = open_dataset(f"array:{real_scan_path}")[0]
    # The bound (< 30 s on CPU) on the process's CPU time with one torch thread (the fixture): at least
    # the wall time an otherwise idle machine would take, and unlike wall time it does not grow when
    # other jobs share the cores (a training run beside the tests once made this 54 s wall, 15 s idle).
    t0 = time.process_time()
    hybrid = segment_hybrid(loaded.model, loaded.config, s.coord, s.color)
    assert time.process_time() - t0 < 30
    learned = segment_points(loaded.model, loaded.config, s.coord, s.color)
    geo = segment_geometric(s.coord)
    ap50 = {name: summarize([match_scene(s.instance, x.masks, x.scores, valid=s.valid)])["AP50"]
            for name, x in (("hybrid", hybrid), ("learned", learned), ("geometric", geo))}
    assert ap50["hybrid"] > ap50["geometric"], ap50
