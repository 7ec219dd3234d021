"""A fixed voxel grid over a scene and its packed linear voxel keys.

Voxel centres sit on multiples of the voxel size (the grid is offset by half a voxel from the
origin), so walls and floors at round coordinates fall in the middle of a voxel layer instead of
on a voxel face, where float noise would split them over two layers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.errors import RenderError

__all__ = ["VoxelGrid", "pick_one_per_voxel", "pick_one_per_voxel_scan"]


@dataclass(frozen=True)
class VoxelGrid:
    """``lo`` (3,) int64 index of the first voxel; ``dims`` (3,) int64 voxels per axis."""

    size: float
    lo: np.ndarray
    dims: np.ndarray

    @staticmethod
    def around(bounds_min: np.ndarray, bounds_max: np.ndarray, size: float, margin: int = 2) -> "VoxelGrid":
        lo = np.floor(np.asarray(bounds_min, np.float64) / size + 0.5).astype(np.int64) - margin
        hi = np.floor(np.asarray(bounds_max, np.float64) / size + 0.5).astype(np.int64) + margin
        dims = hi - lo + 1
        if float(np.prod(dims.astype(np.float64))) >= 2.0 ** 40:
            raise RenderError(f"voxel grid {dims.tolist()} too large for {size} m voxels; the scene spans "
                              f"{np.round(bounds_min, 2).tolist()} to {np.round(bounds_max, 2).tolist()}")
        return VoxelGrid(float(size), lo, dims)

    @property
    def count(self) -> int:
        return int(np.prod(self.dims))

    def keys(self, points: np.ndarray) -> np.ndarray:
        """(N,) int64 linear voxel index of points (N, 3) float32; points outside are clamped to
        the border. Computed column by column (1-d loops are several times faster than (N, 3)
        broadcasts)."""
        return self.keys_of_columns([points[:, 0], points[:, 1], points[:, 2]])

    def keys_of_columns(self, columns: list[np.ndarray]) -> np.ndarray:
        """:meth:`keys` of the points whose x, y and z are ``columns`` (three (N,) float32 arrays)."""
        inv = np.float32(1.0 / self.size)
        half = np.float32(0.5)
        key = np.zeros(len(columns[0]), np.int64)
        for j in range(3):
            q = columns[j] * inv
            q += half
            np.floor(q, out=q)
            ij = q.astype(np.int64)
            ij -= self.lo[j]
            np.clip(ij, 0, self.dims[j] - 1, out=ij)
            if j:
                key *= self.dims[j]
            key += ij
        return key

    def indices(self, keys: np.ndarray) -> np.ndarray:
        """(N, 3) int64 voxel indices (from ``lo``) of linear keys (N,) int64; inverse of :meth:`keys`."""
        out = np.zeros((len(keys), 3), np.int64)
        rest = np.asarray(keys, np.int64)
        for j in (2, 1):
            rest, out[:, j] = np.divmod(rest, self.dims[j])
        out[:, 0] = rest
        return out

    def centers(self, keys: np.ndarray) -> np.ndarray:
        """(N, 3) float64 world centres of the voxels with linear keys (N,) int64."""
        return (self.indices(keys) + self.lo) * self.size


def _mix(keys: np.ndarray, salt: int) -> np.ndarray:
    """(N,) uint64 well-mixed hash of int64 keys and a salt (splitmix64 finaliser)."""
    x = keys.astype(np.uint64) + np.uint64(int(salt) & 0xFFFFFFFFFFFFFFFF)
    x *= np.uint64(0xBF58476D1CE4E5B9)
    x ^= x >> np.uint64(31)
    x *= np.uint64(0x94D049BB133111EB)
    x ^= x >> np.uint64(29)
    return x


def _bits(n: int) -> int:
    return max(1, int(n - 1).bit_length())


def pick_one_per_voxel(keys: np.ndarray, salt: int) -> np.ndarray:
    """Indices (sorted by voxel) of one pseudo-randomly chosen row per distinct voxel key.

    keys: (N,) int64 voxel keys >= 0. The choice inside a voxel is the row whose index, XOR-ed with
    a hash of (voxel, ``salt``), is smallest: uniform-looking, deterministic, and done with one
    integer sort instead of an argsort.
    """
    n = len(keys)
    if n == 0:
        return np.zeros(0, np.int64)
    rb = _bits(n)
    if int(keys.max()).bit_length() + rb > 63:
        raise RenderError(f"voxel keys too wide to pack with {n} rows; raise render.voxel_size")
    mask = np.uint64((1 << rb) - 1)
    h = _mix(keys, salt) & mask
    packed = (keys.astype(np.uint64) << np.uint64(rb)) | (np.arange(n, dtype=np.uint64) ^ h)
    packed.sort()
    vox = packed >> np.uint64(rb)
    first = np.ones(n, dtype=bool)
    first[1:] = vox[1:] != vox[:-1]
    win = packed[first]
    wvox = win >> np.uint64(rb)
    hw = _mix(wvox.astype(np.int64), salt) & mask
    return ((win & mask) ^ hw).astype(np.int64)


def pick_one_per_voxel_scan(keys: np.ndarray, salt: int) -> np.ndarray:
    """Like :func:`pick_one_per_voxel` for keys in image scan order, where neighbouring pixels
    mostly share a voxel: each run of equal consecutive keys first contributes one pseudo-random
    member, and only those (~5x fewer at 2 cm and 640 x 480) are sorted."""
    n = len(keys)
    if n == 0:
        return np.zeros(0, np.int64)
    change = np.flatnonzero(keys[1:] != keys[:-1]) + 1
    starts = np.zeros(len(change) + 1, np.int64)
    starts[1:] = change
    lengths = np.diff(np.append(starts, n))
    h = _mix(keys[starts], ~int(salt))
    cand = starts + (h % lengths.astype(np.uint64)).astype(np.int64)
    return cand[pick_one_per_voxel(keys[cand], salt)]
