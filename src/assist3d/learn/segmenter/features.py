"""Voxels and per-voxel input features of the CPU segmenter (numpy only).

Everything here is computed on **voxel centres**, not on raw points, so the features do not depend on
how densely a scan was sampled (a ScanNet scan subsampled to 50,000 vertices and a generated cloud of
300,000 fused depth points give the same features for the same surface):

* ``height``: metres above the floor, the floor being a low percentile of the voxel heights
  (:func:`floor_height`; generated floors lie at z = 0, real ones anywhere near it).
* ``|n_z|``: how horizontal the local surface is (PCA normal of the ``k`` nearest voxel centres).
* linearity, planarity, scattering: the eigenvalue shape of the same neighbourhood
  ((l1 - l2) / l1, (l2 - l3) / l1, l3 / l1), which separates walls and floors from furniture.

All are invariant to rotations about z, so z-rotation augmentation does not change them.
With ``use_color`` the mean RGB of each voxel (0-1, centred on 0.5) is appended.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..engine.voxelize import VoxelGridError, majority_label, voxel_bins  # noqa: F401  VoxelGridError: the API

#: Channels of the geometry-only input, in order.
GEOMETRY_CHANNELS: tuple[str, ...] = ("one", "height", "abs_nz", "linearity", "planarity", "scattering")
COLOR_CHANNELS: tuple[str, ...] = ("r", "g", "b")


#: Up axes a scan may come with, and the proper rotation (rows: the new x, y, z) that turns each to +z.
#: Every rotation is a signed permutation, so converting is exact in floating point.
UP_AXES: dict[str, tuple[tuple[int, int, int], ...]] = {
    "z": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
    "-z": ((1, 0, 0), (0, -1, 0), (0, 0, -1)),
    "y": ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
    "-y": ((1, 0, 0), (0, 0, 1), (0, -1, 0)),
    "x": ((0, 1, 0), (0, 0, 1), (1, 0, 0)),
    "-x": ((0, -1, 0), (0, 0, 1), (-1, 0, 0)),
}
#: Length units a scan may come in, as metres per unit.
UNITS: dict[str, float] = {"m": 1.0, "cm": 0.01, "mm": 0.001}


def to_segmenter_frame(coord: np.ndarray, up: str = "z", units: str = "m") -> np.ndarray:
    """(N, 3) float32 ``coord`` turned into the segmenter's frame: metres, z up (what its height and
    ``|n_z|`` features, the floor estimate and the geometric reference's structural planes assume).
    ``up`` is the scan's up axis (``UP_AXES``: many mesh exports are y-up), ``units`` its length unit
    (``UNITS``). A proper rotation (no mirror), so instances keep their handedness; the default is
    the identity and returns ``coord`` as float32."""
    if up not in UP_AXES:
        raise ValueError(f"up axis {up!r}: expected one of {', '.join(UP_AXES)}")
    if units not in UNITS:
        raise ValueError(f"units {units!r}: expected one of {', '.join(UNITS)}")
    out = np.asarray(coord, np.float32)
    if up != "z":
        rot = np.asarray(UP_AXES[up])
        # A signed permutation: pick and negate columns (no products with zeros, so inf stays inf).
        out = out[:, np.abs(rot).argmax(1)] * rot.sum(1).astype(np.float32)
    if units != "m":
        out = (out.astype(np.float64) * UNITS[units]).astype(np.float32)
    return out


def num_channels(use_color: bool) -> int:
    return len(GEOMETRY_CHANNELS) + (len(COLOR_CHANNELS) if use_color else 0)


@dataclass(frozen=True)
class Voxels:
    """One scene binned into cubes of ``size`` metres.

    coords (V, 3) int32 non-negative voxel indices; centres (V, 3) float64 metres (in the input frame);
    color (V, 3) float32 mean colour 0-1; instance (V,) int64 majority instance id (-1 none);
    inverse (N,) int64 voxel row of every input point; counts (V,) int64 points per voxel.
    """

    size: float
    coords: np.ndarray
    centres: np.ndarray
    color: np.ndarray
    instance: np.ndarray
    inverse: np.ndarray
    counts: np.ndarray

    def __len__(self) -> int:
        return len(self.coords)


def voxelize(coord: np.ndarray, size: float, color: np.ndarray | None = None,
             instance: np.ndarray | None = None) -> Voxels:
    """Bin ``coord`` (N, 3) metres into ``size`` m voxels; colour is averaged, instance ids voted."""
    if coord.ndim != 2 or coord.shape[1] != 3 or len(coord) == 0:
        raise ValueError(f"coord must be a non-empty (N, 3) array, got shape {coord.shape}")
    if not np.all(np.isfinite(coord)):
        raise ValueError("coord holds non-finite values (NaN or inf)")
    bins = voxel_bins(coord, size)
    inverse, counts, coords = bins.inverse, bins.counts, bins.coords
    v = len(coords)
    centres = (coords + bins.origin + 0.5) * size
    col = np.zeros((v, 3), np.float64)
    if color is not None:
        for c in range(3):
            col[:, c] = np.bincount(inverse, weights=color[:, c].astype(np.float64), minlength=v)
        col /= counts[:, None] * 255.0
    inst = np.full(v, -1, np.int64)
    if instance is not None:
        inst = majority_label(inverse, instance.astype(np.int64), v)
    return Voxels(size=size, coords=coords.astype(np.int32), centres=centres, color=col.astype(np.float32),
                  instance=inst, inverse=inverse.astype(np.int64), counts=counts.astype(np.int64))


def floor_height(centres: np.ndarray, percentile: float = 2.0) -> float:
    """The floor's height: a low percentile of the voxel-centre heights (robust to a few stray points)."""
    return float(np.percentile(centres[:, 2], percentile)) if len(centres) else 0.0


def neighbourhood_scatter(centres: np.ndarray, k: int, tree: cKDTree | None = None) -> np.ndarray:
    """(V, 3, 3) scatter matrix (sum of outer products, centred) of each row's ``k`` nearest rows of
    ``centres`` (V, 3); its smallest-eigenvalue eigenvector is the PCA normal. The neighbour search
    runs on every core (the same neighbours as on one)."""
    k = min(k, len(centres))
    _, idx = (tree or cKDTree(centres)).query(centres, k=k, workers=-1)
    nb = centres[idx.reshape(len(centres), k)]  # (V, k, 3)
    nb = nb - nb.mean(1, keepdims=True)
    return np.einsum("vki,vkj->vij", nb, nb)


def shape_features(centres: np.ndarray, k: int = 12) -> np.ndarray:
    """``(V, 4)`` float32: |n_z|, linearity, planarity, scattering of each voxel's ``k`` nearest centres."""
    v = len(centres)
    out = np.zeros((v, 4), np.float32)
    if v < 3:
        return out
    w, vec = np.linalg.eigh(neighbourhood_scatter(centres, k) / min(k, v))  # ascending eigenvalues
    w = np.maximum(w, 0.0)
    l1 = np.maximum(w[:, 2], 1e-12)
    out[:, 0] = np.abs(vec[:, 2, 0])  # z component of the smallest eigenvector
    out[:, 1] = (w[:, 2] - w[:, 1]) / l1
    out[:, 2] = (w[:, 1] - w[:, 0]) / l1
    out[:, 3] = w[:, 0] / l1
    return out


def voxel_features(vox: Voxels, *, use_color: bool, floor_z: float | None = None) -> np.ndarray:
    """Input features ``(V, C)`` float32 of :data:`GEOMETRY_CHANNELS` (+ :data:`COLOR_CHANNELS`)."""
    fz = floor_height(vox.centres) if floor_z is None else floor_z
    height = (vox.centres[:, 2] - fz).astype(np.float32)
    parts = [np.ones((len(vox), 1), np.float32), height[:, None] / 2.0, shape_features(vox.centres)]
    if use_color:
        parts.append(vox.color - 0.5)
    return np.concatenate(parts, 1).astype(np.float32)
