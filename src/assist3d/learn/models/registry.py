"""One registry of models: a name maps to a builder ``(config section) -> torch.nn.Module``.

Each model registers itself in the module that defines it::

    from assist3d.learn.models.registry import MODELS

    @MODELS.register("my-net")
    def _build(cfg: MyNetConfig) -> nn.Module:
        return MyNet(cfg.width)

and :mod:`assist3d.learn.zoo` imports every built-in model module, so
``zoo.build_model("segmenter", cfg.net)`` finds it. A new model is one file and one import line there.
"""

from __future__ import annotations

from typing import Any, Callable

from torch import nn

from ...core.registry import Registry

#: model builders by name: ``segmenter`` (the CPU segmenter, :class:`~assist3d.learn.segmenter.model.Segmenter`,
#: built from a ``NetConfig``) and ``mask3d`` (the Mask3D-style model, built from a ``ModelConfig``)
MODELS: Registry[Callable[[Any], nn.Module]] = Registry("model")


def build_model(name: str, cfg: Any) -> nn.Module:
    """The model registered as ``name`` built from its config section ``cfg`` (unknown names are
    refused with the closest registered one). Import :mod:`assist3d.learn.zoo` (or the model's
    own module) first so that the entry exists."""
    return MODELS.get(name)(cfg)
