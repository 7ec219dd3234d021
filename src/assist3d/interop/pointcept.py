"""Class-agnostic training on assist3d folders with Pointcept's own code.

Pointcept's ``ScanNetDataset`` reads a generated scene folder as it is (``coord``, ``color``,
``normal``, ``segment20``, ``instance``; the split lists ``train.json`` / ``val.json``). For
class-agnostic instance segmentation a configuration wants three semantic classes, the room's wall
and floor (ignored as instances, as in every ScanNet configuration) and "object";
``Assist3DAgnosticDataset`` is ``ScanNetDataset`` with ``segment20`` folded so: 0 wall and 1 floor
stay, every object class becomes 2, -1 (unlabelled: the ceiling) stays.

A Pointcept configuration loads it with ``custom_imports = dict(imports=["assist3d.interop.pointcept"])``
(``configs/pointcept/``; docs/ecosystem.md). The module needs only numpy and, inside a Pointcept
environment, Pointcept itself; without Pointcept only :func:`agnostic_segment` is defined.
"""

from __future__ import annotations

import numpy as np

__all__ = ["AGNOSTIC_CLASSES", "agnostic_segment"]

#: The semantic classes of class-agnostic training, in index order.
AGNOSTIC_CLASSES: tuple[str, ...] = ("wall", "floor", "object")


def agnostic_segment(segment20: np.ndarray) -> np.ndarray:
    """``segment20`` (ScanNet-20 indices, -1 = none) folded to :data:`AGNOSTIC_CLASSES`, int32."""
    s = np.asarray(segment20).astype(np.int32)
    return np.where(s >= 2, 2, s).astype(np.int32)


try:  # inside a Pointcept environment: register the dataset class
    from pointcept.datasets.builder import DATASETS
    from pointcept.datasets.scannet import ScanNetDataset
except ImportError:  # not inside one (our own tests, a plain install): the mapping alone
    DATASETS = None

if DATASETS is not None:
    @DATASETS.register_module()
    class Assist3DAgnosticDataset(ScanNetDataset):  # type: ignore[misc, valid-type]
        """Pointcept's ``ScanNetDataset`` with ``segment`` folded to wall / floor / object."""

        def get_data(self, idx):
            data = super().get_data(idx)
            data["segment"] = agnostic_segment(data["segment"])
            return data

    __all__ += ["Assist3DAgnosticDataset"]
