"""The built-in models, registered in :data:`~assist3d.learn.models.registry.MODELS` on import.

Import ``build_model`` from here (``from assist3d.learn.zoo import build_model``): every model below is
then registered. Adding a model: write its module with ``@MODELS.register("name")`` and add one import
line here. Inside the package, each trainer imports the registry and its own model's module instead, so
that no learning folder imports another one back.
"""

from __future__ import annotations

from .models import mask3d as _mask3d  # noqa: F401  registers "mask3d"
from .models.registry import MODELS, build_model
from .segmenter import model as _segmenter  # noqa: F401  registers "segmenter"

__all__ = ["MODELS", "build_model"]
