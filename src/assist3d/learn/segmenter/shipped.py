"""Where the model shipped inside the package lies (trained on generated data only; experiments/fidelity-log.md)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from ...core.errors import DataError

SHIPPED_NAME = "segmenter-v3.pt"


def shipped_model_path() -> Path:
    path = Path(str(resources.files("assist3d").joinpath("resources", "models", SHIPPED_NAME)))
    if not path.is_file():
        raise DataError(f"{path}: the shipped segmenter is missing from this install; pass --checkpoint FILE "
                        "(a model written by `assist3d probe`, OUT/seed_0/model.pt)")
    return path
