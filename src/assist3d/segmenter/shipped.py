"""Where the model shipped inside the package lies (trained on generated data only; docs/fidelity.md)."""

from __future__ import annotations

from pathlib import Path

from ..errors import DataError

SHIPPED_NAME = "segmenter-v1.pt"


def shipped_model_path() -> Path:
    path = Path(__file__).resolve().parent.parent / "resources" / "models" / SHIPPED_NAME
    if not path.is_file():
        raise DataError(f"{path}: the shipped segmenter is missing from this install; pass --checkpoint FILE "
                        "(a model written by `assist3d probe`, OUT/seed_0/model.pt)")
    return path
