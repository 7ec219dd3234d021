"""Label check: re-cast rays from the vantage points to every point and compare instance ids.

Every rendered point was seen from one of the vantage points, and all views of a vantage point
share its centre, so the segment from a centre to the point retraces the original ray. A point
counts as *checked* when the re-cast ray from some centre ends at the point (within ``tol``);
it *agrees* when the re-cast hit's instance equals the point's instance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.contracts import PointSample, SceneMesh
from .raycast import RayCaster

__all__ = ["LabelCheck", "verify_labels"]


@dataclass(frozen=True)
class LabelCheck:
    """Outcome of :func:`verify_labels`."""

    points: int
    checked: int
    agree: int
    background_with_instance: int  # points on a background surface that carry an instance id
    visible_instances: tuple[int, ...]  # instances some rendered pixel saw
    missing_instances: tuple[int, ...]  # visible instances without any point

    @property
    def agreement(self) -> float:
        return self.agree / self.checked if self.checked else 1.0

    def ok(self, min_agreement: float = 0.999) -> bool:
        """Acceptance: agreement >= ``min_agreement``, no labelled background, nothing missing."""
        return self.agreement >= min_agreement and self.background_with_instance == 0 and not self.missing_instances

    def to_json(self) -> dict:
        return {"points": self.points, "checked": self.checked, "agree": self.agree,
                "agreement": round(self.agreement, 6), "background_with_instance": self.background_with_instance,
                "visible_instances": len(self.visible_instances), "missing_instances": list(self.missing_instances)}


def verify_labels(scene: SceneMesh, caster: RayCaster, sample: PointSample, centers: np.ndarray, *,
                  pixel_counts: np.ndarray | None = None, tol: float = 0.01, min_pixels: int = 1) -> LabelCheck:
    """Re-cast from each centre (K, 3) to each point of ``sample`` and compare instance ids.

    ``pixel_counts`` (I,) rendered pixels per instance id (from the render); instances with at
    least ``min_pixels`` pixels must have points.
    """
    coord = sample.coord
    n = len(coord)
    hit_inst = np.full(n, -2, np.int64)  # -2 = not yet seen from any centre
    for c in np.asarray(centers, dtype=np.float32):
        todo = np.flatnonzero(hit_inst == -2)
        if len(todo) == 0:
            break
        d = coord[todo] - c
        origins = np.zeros_like(d)
        origins[:] = c
        t, face = caster.cast(origins, d)
        length = np.linalg.norm(d, axis=1)
        seen = (face >= 0) & (np.abs(t - 1.0) * length <= tol)
        hit_inst[todo[seen]] = scene.face_instance[face[seen]]
    checked = hit_inst != -2
    inst = sample.instance.astype(np.int64)
    agree = int(np.count_nonzero(checked & (hit_inst == inst)))
    bg_bad = int(np.count_nonzero(checked & (hit_inst == -1) & (inst != -1)))
    visible: tuple[int, ...] = ()
    missing: tuple[int, ...] = ()
    if pixel_counts is not None:
        visible = tuple(int(i) for i in np.flatnonzero(np.asarray(pixel_counts) >= min_pixels))
        have = set(np.unique(sample.instance).tolist())
        missing = tuple(i for i in visible if i not in have)
    return LabelCheck(n, int(np.count_nonzero(checked)), agree, bg_bad, visible, missing)
