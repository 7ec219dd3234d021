"""Voxelisation of point clouds (numpy) and batch collation (torch).

A scene's points are binned into ``voxel_size`` cubes; each voxel keeps the mean colour of its points
and the majority instance id. ``inverse`` maps every input point to its voxel row, so per-voxel
predictions go back to the reader's points exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...core.errors import DataError


class VoxelGridError(DataError, ValueError):
    """A scene too large for the voxel grid at this voxel size (a ValueError, as before)."""

# ScanNet colour statistics (0-1 range), the usual normalisation of Mask3D-style models.
COLOR_MEAN = np.array([0.47793125906962, 0.4303257521323044, 0.3749598901421883], dtype=np.float32)
COLOR_STD = np.array([0.2834475483823543, 0.27566157565723015, 0.27018971370874995], dtype=np.float32)


@dataclass(frozen=True)
class VoxelBins:
    """Points binned into cubes: ``coords`` (V, 3) int64 cube indices from ``origin`` (3,) int64 (the
    smallest cube index of the scene), ``inverse`` (N,) the cube row of each point, ``counts`` (V,) points
    per cube; cubes ordered by their packed index."""

    coords: np.ndarray
    origin: np.ndarray
    inverse: np.ndarray
    counts: np.ndarray


def voxel_bins(coord: np.ndarray, size: float) -> VoxelBins:
    """Bin ``coord`` (N, 3) metres into ``size`` m cubes: the one grid every voxeliser of the learning side
    uses (this model's :func:`voxelize` and the CPU segmenter's). A scene wider than 2^15 cubes along an
    axis is refused with :class:`VoxelGridError` (the cube index is packed into 16 bits per axis)."""
    grid = np.floor(coord.astype(np.float64) / size).astype(np.int64)
    origin = grid.min(0)
    grid -= origin
    if grid.max() >= 2 ** 15:
        raise VoxelGridError(f"the scene spans {grid.max() * size:.0f} m ({grid.max()} voxels of {size} m) along an "
                             f"axis; the limit is {2 ** 15} voxels, {2 ** 15 * size:.0f} m (is it in millimetres? "
                             "or enlarge the voxel size, or crop the scene)")
    keys = (grid[:, 0] << 32) | (grid[:, 1] << 16) | grid[:, 2]
    _, first, inverse, counts = np.unique(keys, return_index=True, return_inverse=True, return_counts=True)
    return VoxelBins(coords=grid[first], origin=origin, inverse=inverse.reshape(-1), counts=counts)


@dataclass(frozen=True)
class VoxelScene:
    """One voxelised scene.

    coords (V, 3) int32 voxel indices (non-negative); feats (V, 3) float32 normalised RGB;
    instance (V,) int32 majority instance id (-1 = none); inverse (N,) int64 voxel row of each point.
    """

    coords: np.ndarray
    feats: np.ndarray
    instance: np.ndarray
    inverse: np.ndarray


def voxelize(coord: np.ndarray, color: np.ndarray, instance: np.ndarray | None, voxel_size: float) -> VoxelScene:
    """Bin ``coord`` (N, 3) float metres with ``color`` (N, 3) uint8/float 0-255 into voxels of ``voxel_size`` m."""
    if coord.ndim != 2 or coord.shape[1] != 3 or len(coord) == 0:
        raise ValueError(f"coord must be a non-empty (N, 3) array, got shape {coord.shape}")
    if voxel_size <= 0:
        raise ValueError(f"voxel_size must be positive, got {voxel_size}")
    bins = voxel_bins(coord, voxel_size)
    inverse, v = bins.inverse, len(bins.coords)
    coords = bins.coords.astype(np.int32)
    counts = bins.counts.astype(np.float64)
    col = np.zeros((v, 3), dtype=np.float64)
    np.add.at(col, inverse, color.astype(np.float64))
    col = (col / counts[:, None] / 255.0).astype(np.float32)
    feats = (col - COLOR_MEAN) / COLOR_STD
    if instance is None:
        inst = np.full(v, -1, dtype=np.int32)
    else:
        inst = majority_label(inverse, instance.astype(np.int64), v).astype(np.int32)
    return VoxelScene(coords=coords, feats=feats.astype(np.float32), instance=inst, inverse=inverse.astype(np.int64))


def majority_label(group: np.ndarray, label: np.ndarray, n_groups: int) -> np.ndarray:
    """Most frequent ``label`` per ``group`` (ties: smallest label); ``(n_groups,) int64``."""
    group, label = np.asarray(group, np.int64), np.asarray(label, np.int64)
    if len(group) == 0:
        return np.full(n_groups, -1, dtype=np.int64)
    lo = int(label.min())
    span = int(label.max()) - lo + 1
    if int(group.max()) < 2 ** 62 // span and int(group.min()) >= 0:
        # the (group, label) pairs as one int64 key, group-major: a 1-D unique (several times faster
        # than a row-wise unique) that yields the same pairs in the same order
        keys, counts = np.unique(group * span + (label - lo), return_counts=True)
        pairs = np.stack([keys // span, keys % span + lo], 1)
    else:
        pairs, counts = np.unique(np.stack([group, label], 1), axis=0, return_counts=True)
    order = np.lexsort((pairs[:, 1], -counts, pairs[:, 0]))
    pairs = pairs[order]
    first = np.ones(len(pairs), dtype=bool)
    first[1:] = pairs[1:, 0] != pairs[:-1, 0]
    out = np.full(n_groups, -1, dtype=np.int64)
    out[pairs[first, 0]] = pairs[first, 1]
    return out


def instance_masks(instance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ground-truth masks from per-voxel ids: ``(G, V) bool`` and the ids ``(G,) int64`` (ids >= 0)."""
    ids = np.unique(instance[instance >= 0]).astype(np.int64)
    return instance[None, :] == ids[:, None], ids


def collate(scenes: list[VoxelScene], device: str = "cpu"):
    """Concatenate voxel scenes into ``(coords (N, 4) int32, feats (N, 3) float32)`` torch tensors."""
    import torch

    coords = np.concatenate([np.concatenate([np.full((len(s.coords), 1), b, np.int32), s.coords], 1)
                             for b, s in enumerate(scenes)])
    feats = np.concatenate([s.feats for s in scenes])
    return torch.from_numpy(coords).to(device), torch.from_numpy(feats).to(device)
