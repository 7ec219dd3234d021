"""The dataset readers live in :mod:`assist3d.data` (a top-level package: generation's outputs, the
benchmarks, the learning side and ``segment`` all read through them). This module keeps the name they had
under ``assist3d.bench`` for code written against it; new code imports :mod:`assist3d.data`."""

from ..data import FORMATS, READERS, Reader, SceneDataset, open_dataset, parse_spec

__all__ = ["FORMATS", "READERS", "Reader", "SceneDataset", "open_dataset", "parse_spec"]
