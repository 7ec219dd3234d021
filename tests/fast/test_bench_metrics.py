"""Data-quality metrics: context complexity on hand-computed cases, plausibility on constructed
layouts, shape descriptors' invariances and the code entropy."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from assist3d.assets.catalog import Catalog
from assist3d.core.contracts import AssetRecord, MeshData, Opening, PlacedInstance, Room, SceneLayout, SupportSurface
from assist3d.bench.metrics.context import context_complexity, per_class_max_cooccurrence
from assist3d.bench.metrics.diversity import code_entropy, fit_codebook, geometry_diversity, geometry_diversity_se
from assist3d.bench.metrics.features import FEATURE_DIM, instance_descriptors, shape_descriptor
from assist3d.bench.metrics.plausibility import score_layout


def test_context_complexity_hand_computed():
    # every class co-occurs with each other class in 2 of its 3 scenes
    assert context_complexity([{"a", "b"}, {"a", "c"}, {"b", "c"}, {"a", "b", "c"}]) == pytest.approx(2 / 3)
    # a: max P(b|a) = 1/3; b: P(a|b) = 1; c never shares a scene: 0 -> (1/3 + 1 + 0) / 3
    assert context_complexity([{"a", "b"}, {"a"}, {"a"}, {"c"}]) == pytest.approx(4 / 9)
    # always together: 1
    assert context_complexity([{"x", "y"}] * 5) == pytest.approx(1.0)
    assert math.isnan(context_complexity([]))
    best = per_class_max_cooccurrence([{"a", "b"}, {"a"}, {"a"}, {"c"}])
    assert best["b"] == ("a", 1.0) and best["a"][1] == pytest.approx(1 / 3)


def test_code_entropy():
    assert code_entropy(np.array([0, 1, 2, 3]), 4) == pytest.approx(math.log(4))
    assert code_entropy(np.zeros(10, np.int64), 4) == pytest.approx(0.0)


def _box_points(size, n, rng):
    m = trimesh.creation.box(size)
    return np.asarray(trimesh.sample.sample_surface(m, n, seed=int(rng.integers(1 << 30)))[0])


def test_descriptor_invariant_to_yaw_and_translation():
    rng = np.random.default_rng(0)
    p = _box_points((1.0, 0.4, 0.8), 3000, rng)
    rot = trimesh.transformations.rotation_matrix(0.7, (0, 0, 1))[:3, :3]
    q = p @ rot.T + np.array([3.0, -2.0, 0.0])
    f1 = shape_descriptor(p, rng=np.random.default_rng(1))
    f2 = shape_descriptor(q, rng=np.random.default_rng(1))
    f3 = shape_descriptor(_box_points((0.1, 0.1, 1.5), 3000, rng), rng=np.random.default_rng(1))
    assert f1.shape == (FEATURE_DIM,)
    # same shape moved: far closer than a different shape
    assert np.linalg.norm(f1 - f2) < 0.25 * np.linalg.norm(f1 - f3)


def test_instance_descriptors_skip_background_and_tiny():
    rng = np.random.default_rng(0)
    pts = np.concatenate([_box_points((1, 1, 1), 500, rng), _box_points((0.2, 0.2, 0.2), 10, rng),
                          _box_points((5, 5, 0.01), 500, rng)]).astype(np.float32)
    inst = np.concatenate([np.full(500, 7), np.full(10, 3), np.full(500, -1)]).astype(np.int32)
    ids, feats = instance_descriptors(pts, inst, rng=rng)
    assert ids.tolist() == [7] and feats.shape == (1, FEATURE_DIM)


def test_geometry_diversity_orders_varied_above_uniform():
    rng = np.random.default_rng(0)
    varied = np.stack([shape_descriptor(_box_points(tuple(rng.uniform(0.05, 2.0, 3)), 800, rng), rng=rng)
                       for _ in range(60)])
    same = np.stack([shape_descriptor(_box_points((0.5, 0.5, 0.5), 800, rng), rng=rng) for _ in range(60)])
    cb = fit_codebook(np.concatenate([varied, same]), k=16, rng=np.random.default_rng(0))
    assert geometry_diversity(varied, cb) > geometry_diversity(same, cb) + 1.0


# --------------------------------------------------------------------------- plausibility


def _mesh(m: trimesh.Trimesh) -> MeshData:
    return MeshData(m.vertices.astype(np.float32), m.faces.astype(np.int32), np.full((len(m.faces), 3), 180, np.uint8))


@pytest.fixture
def catalog(tmp_path):
    cat = Catalog.open_or_create(tmp_path / "lib")

    def add(aid, size, groups, supports=()):
        m = trimesh.creation.box(size)
        m.apply_translation((0, 0, size[2] / 2))
        cat.add(AssetRecord(id=aid, source="test", name=aid, class_name=aid, groups=groups, size=size,
                            supports=supports), _mesh(m))

    add("table", (1.2, 0.8, 0.75), ("floor",),
        (SupportSurface(0.75, ((-0.55, -0.35), (0.55, -0.35), (0.55, 0.35), (-0.55, 0.35))),))
    add("cabinet", (0.8, 0.5, 1.0), ("floor",))
    add("cup", (0.1, 0.1, 0.12), ("obj",))
    add("picture", (0.8, 0.04, 0.6), ("wall",))
    cat.save()
    return cat


def _pose(x, y, z=0.0, yaw=0.0):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0, x], [s, c, 0, y], [0, 0, 1, z], [0, 0, 0, 1]], dtype=np.float64)


ROOM = Room(((0, 0), (5, 0), (5, 4), (0, 4)), 2.8, (Opening("door", 0, 2.5, 0.9, 0.0, 2.0),))


def test_plausible_layout_scores_high(catalog):
    insts = (
        PlacedInstance(1, "table", "table", "floor", _pose(2.5, 2.0)),
        # cabinet with its back (+y) against the north wall, front facing into the room
        PlacedInstance(2, "cabinet", "cabinet", "floor", _pose(1.0, 3.75)),
        PlacedInstance(3, "cup", "cup", "obj", _pose(2.4, 2.1, 0.75), parent=1),
        # picture on the north wall, back at +y against y = 4
        PlacedInstance(4, "picture", "picture", "wall", _pose(3.5, 3.98, 1.5)),
    )
    rep = score_layout(SceneLayout(ROOM, insts, (), seed=0, seconds=0.0), catalog)
    assert rep.problems == ()
    assert rep.score == pytest.approx(100.0)


def test_implausible_layout_scores_low_with_reasons(catalog):
    insts = (
        PlacedInstance(1, "table", "table", "floor", _pose(2.5, 2.0)),
        PlacedInstance(2, "cabinet", "cabinet", "floor", _pose(2.7, 2.1)),            # inside the table
        PlacedInstance(3, "cup", "cup", "obj", _pose(1.0, 1.0, 0.4)),                 # floating
        PlacedInstance(4, "picture", "picture", "wall", _pose(2.0, 2.0, 1.5)),        # mid-room
        PlacedInstance(5, "cabinet", "cabinet", "floor", _pose(5.2, 1.0)),            # through the wall
        PlacedInstance(6, "cabinet", "cabinet", "floor", _pose(1.0, 0.3, 0.0, math.pi)),  # faces... away
        PlacedInstance(7, "cabinet", "cabinet", "floor", _pose(4.0, 0.45)),           # front 0.2 m from a wall
    )
    rep = score_layout(SceneLayout(ROOM, insts, (), seed=0, seconds=0.0), catalog)
    c = rep.components
    assert c["collision_free"] < 1 and c["supported"] < 1 and c["inside"] < 1 and c["on_wall"] == 0
    assert c["not_facing_wall"] < 1
    text = " ".join(rep.problems)
    assert "interpenetrate" in text and "floating" in text and "outside" in text and "not on a wall" in text
    assert rep.score < 75


def test_blocked_room_is_unreachable(catalog):
    # a wall of cabinets right behind the door cuts the room in two
    insts = tuple(PlacedInstance(i + 1, "cabinet", "cabinet", "floor", _pose(0.4 + 0.8 * i, 1.0, 0.0, 0.0))
                  for i in range(7))
    rep = score_layout(SceneLayout(ROOM, insts, (), seed=0, seconds=0.0), catalog)
    assert rep.components["reachable"] < 0.5


def test_asset_feature_cache_is_reused(catalog, monkeypatch):
    """The second call reads <catalog>/features.npz instead of describing meshes again (it used to
    fail on its own cache: the seed came back as shape (1,))."""
    from assist3d.bench.metrics import clusters

    ids, feats = clusters.asset_features(catalog)
    assert sorted(ids) == ["cabinet", "cup", "picture", "table"] and feats.shape == (4, FEATURE_DIM)
    with np.load(catalog.root / clusters.FEATURES_FILE) as z:
        assert z["seed"].shape == ()

    def fail(*a, **k):
        raise AssertionError("descriptor recomputed although cached")

    monkeypatch.setattr(clusters, "mesh_descriptor", fail)
    ids2, feats2 = clusters.asset_features(catalog)
    assert ids2 == ids and np.array_equal(feats2, feats)
    # another seed is a different cache: recomputed
    with pytest.raises(AssertionError, match="recomputed"):
        clusters.asset_features(catalog, seed=1)


@pytest.mark.slow
def test_geometry_diversity_se_tracks_the_spread_over_fresh_draws_of_scenes():
    """The scene resampling's standard error is about the true spread of the value over fresh datasets
    when a scene's objects share shapes; resampling instances instead would miss most of it."""
    k = 16
    shares = np.random.default_rng(0).dirichlet(np.full(k, 0.7))

    def dataset(rng, scenes=40):  # each scene holds 10-29 objects of two of the codes
        return [rng.choice(rng.choice(k, 2, p=shares, replace=False), rng.integers(10, 30)) for _ in range(scenes)]

    rng = np.random.default_rng(1)
    true = np.std([code_entropy(np.concatenate(dataset(rng)), k) for _ in range(300)], ddof=1)
    ses = [geometry_diversity_se(dataset(rng), k, np.random.default_rng(i))[0] for i in range(12)]
    assert 0.75 < np.mean(ses) / true < 1.3
    flat = np.concatenate(dataset(rng))
    per_instance = geometry_diversity_se([flat[i:i + 1] for i in range(len(flat))], k, np.random.default_rng(0))[0]
    assert per_instance / true < 0.6
    # reproducible, an empty scene is harmless, and one scene gives no standard error
    d = dataset(np.random.default_rng(2), scenes=10)
    assert geometry_diversity_se(d, k, np.random.default_rng(3)) == geometry_diversity_se(d, k, np.random.default_rng(3))
    assert geometry_diversity_se(d + [np.zeros(0, np.int64)], k, np.random.default_rng(3))[0] > 0
    assert geometry_diversity_se(d[:1], k, np.random.default_rng(3)) == (None, "fewer than 2 scenes")
    assert geometry_diversity_se([np.zeros(0, np.int64)] * 3, k, np.random.default_rng(3))[0] is None
