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
    return _scatter(centres, idx.reshape(len(centres), k))


def _scatter(centres: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """(V, 3, 3) centred scatter matrix of the rows ``idx`` (V, k) of ``centres``."""
    nb = centres[idx]  # (V, k, 3)
    nb = nb - nb.mean(1, keepdims=True)
    return np.einsum("vki,vkj->vij", nb, nb)


#: a neighbourhood whose two smallest eigenvalues are closer than this (relative to the largest) is
#: (nearly) degenerate: its normal is not fixed by the closed form, so LAPACK decides it as before
_DEGENERATE = 1e-6


def _scatter_entries(centres: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, ...]:
    """The six entries ``xx, yy, zz, xy, xz, yz`` ((V,) float64 each) of the mean-centred scatter
    matrix of each row's neighbours ``idx`` (V, k), divided by k: per axis one gather, no (V, k, 3)
    array and no batched 3 x 3 products."""
    k = idx.shape[1]
    d = []
    for a in range(3):
        x = np.ascontiguousarray(centres[:, a])[idx]  # (V, k)
        x -= x.mean(1, keepdims=True)
        d.append(x)
    x, y, z = d
    return tuple(np.einsum("ij,ij->i", p, q) / k for p, q in ((x, x), (y, y), (z, z), (x, y), (x, z), (y, z)))


def _eigen_sym3(xx: np.ndarray, yy: np.ndarray, zz: np.ndarray, xy: np.ndarray, xz: np.ndarray,
                yz: np.ndarray) -> tuple[np.ndarray, ...]:
    """Eigenvalues ``(w0 <= w1 <= w2)`` of the symmetric 3 x 3 matrices given by their six entries, and
    the unit eigenvector ``(nx, ny, nz)`` of ``w0``, in closed form (float64): the eigenvalues by the
    trigonometric solution of the characteristic cubic, the eigenvector as the longest cross product
    of two rows of ``A - w0 I``. Valid where ``w0`` is a simple eigenvalue (see :data:`_DEGENERATE`)."""
    q = (xx + yy + zz) / 3.0
    a, b, c = xx - q, yy - q, zz - q
    p = np.sqrt((a * a + b * b + c * c + 2.0 * (xy * xy + xz * xz + yz * yz)) / 6.0)
    det = a * (b * c - yz * yz) - xy * (xy * c - yz * xz) + xz * (xy * yz - b * xz)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(p > 0, det / (2.0 * p ** 3), 0.0)
    phi = np.arccos(np.clip(r, -1.0, 1.0)) / 3.0
    w2 = q + 2.0 * p * np.cos(phi)
    w0 = q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    w1 = 3.0 * q - w2 - w0
    r0 = np.stack([xx - w0, xy, xz], 1)
    r1 = np.stack([xy, yy - w0, yz], 1)
    r2 = np.stack([xz, yz, zz - w0], 1)
    cands = np.stack([np.cross(r0, r1), np.cross(r0, r2), np.cross(r1, r2)], 1)  # (V, 3, 3)
    norm2 = np.einsum("vcj,vcj->vc", cands, cands)
    best = norm2.argmax(1)
    rows = np.arange(len(q))
    vec = cands[rows, best] / np.sqrt(np.maximum(norm2[rows, best], 1e-300))[:, None]
    return w0, w1, w2, vec[:, 0], vec[:, 1], vec[:, 2]


def shape_features(centres: np.ndarray, k: int = 12) -> np.ndarray:
    """``(V, 4)`` float32: |n_z|, linearity, planarity, scattering of each voxel's ``k`` nearest centres.

    The PCA of each neighbourhood is solved in closed form (:func:`_eigen_sym3`), which is several
    times faster than a batched LAPACK call and agrees with it to about 1e-8; neighbourhoods whose
    normal the closed form cannot fix (two equal smallest eigenvalues, e.g. voxels on a line) are
    solved by ``numpy.linalg.eigh`` exactly as before, so they get the same normal."""
    v = len(centres)
    out = np.zeros((v, 4), np.float32)
    if v < 3:
        return out
    kk = min(k, v)
    _, idx = cKDTree(centres).query(centres, k=kk, workers=-1)
    idx = idx.reshape(v, kk)
    w0, w1, w2, _, _, nz = _eigen_sym3(*_scatter_entries(centres, idx))
    nz = np.abs(nz)
    odd = np.flatnonzero(~(w1 - w0 > _DEGENERATE * np.maximum(w2, 0.0)))  # NaN-safe
    if len(odd):  # the same computation as before for these rows: the same eigenvectors
        w, vec = np.linalg.eigh(_scatter(centres, idx[odd]) / kk)
        w0[odd], w1[odd], w2[odd] = w[:, 0], w[:, 1], w[:, 2]
        nz[odd] = np.abs(vec[:, 2, 0])
    w0, w1, w2 = np.maximum(w0, 0.0), np.maximum(w1, 0.0), np.maximum(w2, 0.0)
    l1 = np.maximum(w2, 1e-12)
    out[:, 0] = nz
    out[:, 1] = (w2 - w1) / l1
    out[:, 2] = (w1 - w0) / l1
    out[:, 3] = w0 / l1
    return out


def voxel_features(vox: Voxels, *, use_color: bool, floor_z: float | None = None) -> np.ndarray:
    """Input features ``(V, C)`` float32 of :data:`GEOMETRY_CHANNELS` (+ :data:`COLOR_CHANNELS`)."""
    fz = floor_height(vox.centres) if floor_z is None else floor_z
    height = (vox.centres[:, 2] - fz).astype(np.float32)
    parts = [np.ones((len(vox), 1), np.float32), height[:, None] / 2.0, shape_features(vox.centres)]
    if use_color:
        parts.append(vox.color - 0.5)
    return np.concatenate(parts, 1).astype(np.float32)
