"""Geometry diversity: entropy of instance shape codes under a shared k-means codebook.

Entropy values are only comparable when every dataset is coded with the same codebook. A
codebook is fitted once (k-means++ on a reference pool of descriptors, seeded) and can be saved
and reused; ``assist3d metrics`` fits one on a balanced pool drawn from all the datasets it
compares (the same number of instances from each), or loads one given with ``--codebook``.

    H = -sum_k p_k ln p_k,   p_k = share of the dataset's instances whose nearest code is k

in nats; the maximum is ln K (K = 64 codes: 4.16).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np
from scipy.cluster.vq import kmeans2
from scipy.spatial import cKDTree

from ...core import reading
from ...core.errors import DataError, shown
from ...core.fileio import write_npz_atomic

DEFAULT_CODES = 64
SE_DRAWS = 500  # scene resamplings behind geometry_diversity_se


@dataclass(frozen=True)
class Codebook:
    """centers (K, D) float32; ``mean``/``scale`` standardise descriptors before coding."""

    centers: np.ndarray
    mean: np.ndarray
    scale: np.ndarray

    def assign(self, features: np.ndarray) -> np.ndarray:
        """(n,) int64 index of the nearest code of each descriptor."""
        if len(features) == 0:
            return np.zeros(0, np.int64)
        z = (np.asarray(features, np.float64) - self.mean) / self.scale
        return cKDTree(self.centers.astype(np.float64)).query(z)[1].astype(np.int64)

    def save(self, path: str | Path) -> None:
        write_npz_atomic(path, centers=self.centers, mean=self.mean, scale=self.scale)

    @staticmethod
    def load(path: str | Path) -> "Codebook":
        try:
            z = reading.read_npz(path, keys=("centers", "mean", "scale"), what="codebook file")
        except DataError as e:
            raise DataError(f"{shown(path, 400)}: not a codebook file ({reading.problem(e, path)})") from None
        return Codebook(z["centers"], z["mean"], z["scale"])


def fit_codebook(features: np.ndarray, *, k: int = DEFAULT_CODES, rng: np.random.Generator) -> Codebook:
    """k-means++ codebook of ``k`` codes (fewer if there are fewer distinct descriptors)."""
    x = np.asarray(features, np.float64)
    if len(x) == 0:
        raise DataError("cannot fit a shape codebook: no instance descriptors")
    # One global scale, not per-dimension standardisation: the descriptor's blocks are already
    # weighted, and standardising near-constant dimensions would blow sampling noise up.
    mean = x.mean(0)
    scale = np.full(x.shape[1], max(float(x.std()), 1e-6))
    z = (x - mean) / scale
    k = int(min(k, len(np.unique(z.round(6), axis=0))))
    centers, _ = kmeans2(z, k, iter=30, minit="++", seed=rng)
    return Codebook(centers.astype(np.float32), mean.astype(np.float32), scale.astype(np.float32))


def _histogram_entropy(counts: np.ndarray) -> float:
    """Shannon entropy (nats) of a histogram of non-negative counts with a positive sum."""
    p = counts[counts > 0] / counts.sum()
    return float(-(p * np.log(p)).sum())


def code_entropy(codes: np.ndarray, k: int) -> float:
    """Shannon entropy (nats) of the histogram of ``codes`` over ``k`` bins; NaN if empty."""
    if len(codes) == 0:
        return float("nan")
    return _histogram_entropy(np.bincount(codes, minlength=k).astype(np.float64))


def geometry_diversity(features: np.ndarray, codebook: Codebook) -> float:
    return code_entropy(codebook.assign(features), len(codebook.centers))


def geometry_diversity_se(scene_codes: Sequence[np.ndarray], k: int, rng: np.random.Generator,
                          draws: int = SE_DRAWS) -> tuple[float | None, str | None]:
    """``(standard error of the code entropy, reason when None)``: the standard deviation of
    :func:`code_entropy` over ``draws`` resamplings of the scenes with replacement, a scene's codes
    (``scene_codes[i]``, ints in 0..k-1) going together, under the same codebook. It says how far the
    value would move with other scenes from the same generator; the codebook's own spread is
    ``geometry_diversity_sd``. None for fewer than 2 scenes, or when too few resamplings hold an instance.
    """
    n = len(scene_codes)
    if n < 2:
        return None, "fewer than 2 scenes"
    codes = np.concatenate([np.asarray(c, np.int64) for c in scene_codes])
    scene_of = np.repeat(np.arange(n), [len(c) for c in scene_codes])
    ent = []
    for _ in range(draws):  # one resampling at a time: memory stays that of the codes, whatever the scene count
        times = np.bincount(rng.integers(0, n, n), minlength=n)  # how often each scene was drawn
        counts = np.bincount(codes, weights=times[scene_of], minlength=k)
        if counts.sum() > 0:
            ent.append(_histogram_entropy(counts))
    if len(ent) < draws // 2:
        return None, "too few scenes with an instance"
    return float(np.std(ent, ddof=1)), None
