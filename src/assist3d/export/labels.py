"""ScanNet class labels per point, written beside a scene's own arrays: ``segment20.npy`` and
``segment200.npy`` (int32 (N,), the ScanNet-20 and ScanNet200 class index, -1 = none), what
Pointcept's ``ScanNetDataset`` / ``ScanNet200Dataset`` and its ScanNet configurations read.

Objects get the ScanNet class of their class name (:mod:`assist3d.core.taxonomy.scannet`). The
room's points (``instance`` -1) are labelled wall, floor or ceiling from the surface they lie on: the
rendered normal is the surface's own, so a point whose normal points up within 60 degrees in the
lower half of the room is floor, one whose normal points down in the upper half is ceiling, every
other one wall (the shell is a floor polygon extruded to the room height, walls vertical).
"""

from __future__ import annotations

import numpy as np

from ..core.taxonomy.scannet import SURFACES, scannet_label, surface_label

__all__ = ["surface_codes", "scannet_segments", "SURFACE_NORMAL_Z"]

#: |normal z| above which a room point counts as floor or ceiling (cos 60 degrees).
SURFACE_NORMAL_Z = 0.5


def surface_codes(coord: np.ndarray, normal: np.ndarray, instance: np.ndarray, height: float) -> np.ndarray:
    """Per point: -1 for an object point, else 0 wall, 1 floor, 2 ceiling (:data:`SURFACES`)."""
    nz = np.asarray(normal, np.float32)[:, 2]
    z = np.asarray(coord, np.float32)[:, 2]
    codes = np.full(len(nz), SURFACES.index("wall"), np.int32)
    codes[(nz > SURFACE_NORMAL_Z) & (z < height / 2)] = SURFACES.index("floor")
    codes[(nz < -SURFACE_NORMAL_Z) & (z > height / 2)] = SURFACES.index("ceiling")
    codes[np.asarray(instance) >= 0] = -1
    return codes


def scannet_segments(coord: np.ndarray, normal: np.ndarray, instance: np.ndarray, segment: np.ndarray,
                     classes: tuple[str, ...] | list[str], height: float) -> tuple[np.ndarray, np.ndarray]:
    """``(segment20, segment200)`` int32 (N,) of a scene: ``segment`` indexes ``classes``; an object
    point whose class index is -1 or out of range counts as an unmatched class (otherfurniture /
    object)."""
    labels = [scannet_label(c) for c in classes] + [scannet_label("")]  # last: an unknown class
    lut20 = np.array([lab.index20 for lab in labels], np.int32)
    lut200 = np.array([lab.scannet200.index for lab in labels], np.int32)
    seg = np.asarray(segment, np.int64)
    seg = np.where((seg >= 0) & (seg < len(classes)), seg, len(classes))
    seg20, seg200 = lut20[seg], lut200[seg]
    codes = surface_codes(coord, normal, instance, height)
    for code in range(len(SURFACES)):
        lab = surface_label(code)
        m = codes == code
        seg20[m] = lab.index20
        seg200[m] = lab.scannet200.index
    return seg20.astype(np.int32), seg200.astype(np.int32)
