"""The segmenter's shape features: the closed-form PCA equals LAPACK's, degenerate neighbourhoods included."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.learn.segmenter.features import shape_features
from scipy.spatial import cKDTree


def lapack_features(centres: np.ndarray, k: int = 12) -> np.ndarray:
    """The definition: batched ``numpy.linalg.eigh`` of each neighbourhood's centred scatter / k."""
    k = min(k, len(centres))
    _, idx = cKDTree(centres).query(centres, k=k)
    nb = centres[idx.reshape(len(centres), k)]
    nb = nb - nb.mean(1, keepdims=True)
    w, vec = np.linalg.eigh(np.einsum("vki,vkj->vij", nb, nb) / k)
    w = np.maximum(w, 0.0)
    l1 = np.maximum(w[:, 2], 1e-12)
    return np.stack([np.abs(vec[:, 2, 0]), (w[:, 2] - w[:, 1]) / l1, (w[:, 1] - w[:, 0]) / l1, w[:, 0] / l1],
                    1).astype(np.float32)


def _scene(rng: np.random.Generator) -> np.ndarray:
    """5 cm voxel centres of a floor, a wall, a tilted board, a pole (collinear: a degenerate
    neighbourhood) and a noisy blob."""
    g = np.arange(40) * 0.05
    floor = np.stack(np.meshgrid(g, g, [0.0], indexing="ij"), -1).reshape(-1, 3)
    wall = np.stack(np.meshgrid(g, [2.0], g, indexing="ij"), -1).reshape(-1, 3)
    u, v = np.meshgrid(g[:20], g[:20], indexing="ij")
    board = np.stack([0.5 + u.ravel(), 0.5 + 0.6 * v.ravel(), 0.3 + 0.8 * v.ravel()], 1)
    pole = np.stack([np.full(30, 1.5), np.full(30, 1.5), 0.5 + np.arange(30) * 0.05], 1)
    blob = rng.normal([1.0, 1.0, 1.0], 0.1, (300, 3))
    return np.concatenate([floor, wall, board, pole, blob]) + 0.025


@pytest.mark.parametrize("seed", [0, 1])
def test_closed_form_shape_features_equal_lapack(seed):
    centres = _scene(np.random.default_rng(seed))
    got, ref = shape_features(centres), lapack_features(centres)
    assert got.shape == ref.shape == (len(centres), 4) and got.dtype == np.float32
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-6)
    # the pole's inner voxels see only the pole: equal smallest eigenvalues, a normal that the closed
    # form cannot fix, so it must be LAPACK's own choice, to the bit
    pole = slice(3200 + 400, 3200 + 400 + 30)
    inner = np.arange(pole.start + 6, pole.stop - 6)
    assert np.all(ref[inner, 1] > 0.999)  # linear
    np.testing.assert_array_equal(got[inner], ref[inner])


def test_shape_features_of_tiny_inputs():
    assert shape_features(np.zeros((2, 3))).tolist() == [[0.0] * 4] * 2
    three = shape_features(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]))
    np.testing.assert_allclose(three, lapack_features(np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])), atol=1e-6)
    assert three[:, 0].tolist() == [1.0, 1.0, 1.0]  # a horizontal plane: |n_z| = 1
