"""The built-in models, registered in :data:`~assist3d.learn.models.registry.MODELS` on import.

Import ``build_model`` from here: every model below is then registered. Adding a model: write its
module with ``@MODELS.register("name")`` and add one import line here.
"""

from __future__ import annotations

from ..segmenter import model as _segmenter  # noqa: F401  registers "segmenter"
from . import mask3d as _mask3d  # noqa: F401  registers "mask3d"
from .registry import MODELS, build_model

__all__ = ["MODELS", "build_model"]
