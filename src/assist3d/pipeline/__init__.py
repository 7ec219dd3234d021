"""Scene generation: one scene end to end (:mod:`.scene`) and the dataset loop around it
(:mod:`.dataset`: resumable, parallel over processes or a Ray cluster, deterministic per scene).

Scene ``k`` of a dataset with global seed ``S`` uses ``scene_seed(S, k)`` and ``scene_index=k``
everywhere, so it can be regenerated alone and equals the same scene of a full run.
"""

from __future__ import annotations

from ..core.records import STAGES
from .dataset import DatasetRun, generate_dataset, run_benchmark
from .scene import SceneGenerator, SceneJob, scene_name

__all__ = ["STAGES", "scene_name", "SceneJob", "SceneGenerator", "generate_dataset", "DatasetRun", "run_benchmark"]
