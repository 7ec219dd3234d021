"""Context complexity, exactly as the paper defines it.

For every class c that occurs in at least one scene, and every other class c', the probability
that c' occurs in a scene containing c:  P(c' | c) = #scenes containing c and c' / #scenes
containing c. Take the maximum over c' != c, then average over classes c. Lower is better: no
class reliably brings another along. A class that never shares a scene with another class
contributes 0.
"""

from __future__ import annotations

from typing import Iterable, Sequence

import numpy as np


def cooccurrence_matrix(scene_classes: Sequence[Iterable[str]]) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Classes (sorted), scene counts per class (C,), and joint scene counts (C, C)."""
    sets = [set(s) for s in scene_classes]
    classes = sorted(set().union(*sets)) if sets else []
    index = {c: i for i, c in enumerate(classes)}
    occ = np.zeros((len(sets), len(classes)), dtype=np.float64)
    for r, s in enumerate(sets):
        for c in s:
            occ[r, index[c]] = 1.0
    joint = occ.T @ occ
    return classes, np.diag(joint).copy(), joint


def context_complexity(scene_classes: Sequence[Iterable[str]]) -> float:
    """Mean over classes of max over other classes of P(other in scene | class in scene).

    ``scene_classes``: for each scene, the classes of its object instances. NaN if no class.
    """
    classes, counts, joint = cooccurrence_matrix(scene_classes)
    if not classes:
        return float("nan")
    cond = joint / counts[:, None]
    np.fill_diagonal(cond, 0.0)
    return float(cond.max(axis=1).mean()) if len(classes) > 1 else 0.0


def per_class_max_cooccurrence(scene_classes: Sequence[Iterable[str]]) -> dict[str, tuple[str | None, float]]:
    """For each class, its most frequent companion and that conditional probability."""
    classes, counts, joint = cooccurrence_matrix(scene_classes)
    cond = joint / np.maximum(counts[:, None], 1)
    np.fill_diagonal(cond, -1.0)
    out: dict[str, tuple[str | None, float]] = {}
    for i, c in enumerate(classes):
        if len(classes) < 2:
            out[c] = (None, 0.0)
        else:
            j = int(np.argmax(cond[i]))
            out[c] = (classes[j], float(max(cond[i, j], 0.0)))
    return out
