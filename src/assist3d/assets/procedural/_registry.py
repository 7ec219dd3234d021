"""The registry of procedural families: a name, the groups its assets belong to, a builder."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ...core.contracts import GROUPS
from ._build import Shape

Builder = Callable[[np.random.Generator], Shape]


@dataclass(frozen=True)
class Family:
    """A parametric family: ``build(rng)`` draws every shape parameter and colour from ``rng``."""

    name: str
    groups: tuple[str, ...]
    build: Builder
    weight: float = 1.0  # relative frequency among the families of its first group


FAMILIES: dict[str, Family] = {}


def family(name: str, groups: tuple[str, ...], *, weight: float = 1.0) -> Callable[[Builder], Builder]:
    """Register ``fn`` as family ``name`` (decorator)."""
    bad = [g for g in groups if g not in GROUPS]
    if bad or not groups:
        raise ValueError(f"family {name!r}: groups {groups} must be a non-empty subset of {GROUPS}")

    def deco(fn: Builder) -> Builder:
        if name in FAMILIES:
            raise ValueError(f"family {name!r} registered twice")
        FAMILIES[name] = Family(name, tuple(groups), fn, float(weight))
        return fn

    return deco
