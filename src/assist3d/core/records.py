"""Typed run records: what one generated scene reports about itself (its completion marker,
``meta.json``), the part of it the dataset manifest keeps, and the pieces both are made of.

Every module that writes or reads these records goes through this one: the pipeline builds a
:class:`SceneRecord`, the writer adds the file digests, the manifest keeps :meth:`SceneRecord.entry`,
and the command line's summary table and the benchmark read :class:`StageTimings`. A key is named
here once; renaming it here renames it everywhere (and the tests that read markers would fail).

The JSON written is unchanged from earlier releases: same keys, same order.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Any, Mapping

__all__ = ["STAGES", "PLAN_COUNTERS", "StageTimings", "LLMUsage", "SceneRecord", "MANIFEST_ENTRY_KEYS"]

# the stages of one scene, in the order they run (timed per scene, summed in reports)
STAGES = ("select", "layout", "assemble", "render", "fuse", "write")

# counters a relation planner reports per call, summed over a layout's groups (llm_seconds is wall
# time: the layout files it under stats["timing"] with the per-group times; see LLMUsage)
PLAN_COUNTERS = ("llm_calls", "cache_hits", "repairs", "prompt_tokens", "completion_tokens", "llm_seconds")

# the keys of a scene record the dataset manifest keeps, in this order
MANIFEST_ENTRY_KEYS = ("id", "index", "seed", "instances", "points", "seconds", "dropped", "planner", "llm", "check")


@dataclass
class StageTimings:
    """Wall-clock seconds per stage of one scene (``write`` is filled in by the writer)."""

    select: float = 0.0
    layout: float = 0.0
    assemble: float = 0.0
    render: float = 0.0
    fuse: float = 0.0
    write: float | None = None

    def to_json(self) -> dict[str, float]:
        return {s: getattr(self, s) for s in STAGES if getattr(self, s) is not None}

    @classmethod
    def from_json(cls, d: Mapping[str, Any] | None) -> StageTimings:
        d = d or {}
        return cls(**{s: float(d[s]) for s in STAGES if isinstance(d.get(s), (int, float))})

    def get(self, stage: str) -> float:
        """Seconds of ``stage`` (0 when not recorded)."""
        return float(getattr(self, stage) or 0.0)

    @property
    def total(self) -> float:
        return sum(self.get(s) for s in STAGES)


@dataclass(frozen=True)
class LLMUsage:
    """What the relation planner spent on one scene. ``None``: not reported (the rule planner
    reports call counts only; token counts come from endpoints that give them)."""

    llm_calls: int | None = None
    cache_hits: int | None = None
    repairs: int | None = None
    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    llm_seconds: float | None = None

    @classmethod
    def from_layout_stats(cls, stats: Mapping[str, Any]) -> LLMUsage:
        """Read from a layout's ``stats``: the counters at its top level, the seconds with its timings."""
        timing = stats.get("timing") or {}
        found = {}
        for k in PLAN_COUNTERS:
            v = stats.get(k, timing.get(k))
            if isinstance(v, (int, float)):
                found[k] = v
        return cls(**found)

    @classmethod
    def from_json(cls, d: Mapping[str, Any] | None) -> LLMUsage:
        return cls(**{k: v for k, v in (d or {}).items() if k in PLAN_COUNTERS and isinstance(v, (int, float))})

    def to_json(self) -> dict[str, float]:
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) is not None}


@dataclass
class SceneRecord:
    """The completion marker of one scene folder (``meta.json``), as the pipeline builds it.

    The writer (:func:`assist3d.export.write_scene`) adds ``format``, ``version``, ``points``,
    the write time and a digest of every file when it writes the marker.
    """

    id: str
    index: int
    seed: int
    dataset_seed: int
    instances: int
    instances_with_points: int
    dropped: int
    planner: dict[str, str]
    vantage_points: list[list[float]]
    render: dict[str, Any]
    triangles: int
    llm: LLMUsage
    seconds: StageTimings
    cpu_seconds: dict[str, float] = field(default_factory=dict)  # CPU time of this process per stage
    check: dict[str, Any] | None = None  # the label check of --verify

    def to_json(self) -> dict[str, Any]:
        """The marker's fields in the order they are written."""
        out: dict[str, Any] = {
            "id": self.id, "index": self.index, "seed": self.seed, "dataset_seed": self.dataset_seed,
            "instances": self.instances, "instances_with_points": self.instances_with_points,
            "dropped": self.dropped, "planner": dict(self.planner), "vantage_points": self.vantage_points,
            "render": self.render, "triangles": self.triangles, "llm": self.llm.to_json(),
        }
        if self.check is not None:
            out["check"] = self.check
        out["seconds"] = self.seconds.to_json()
        out["cpu_seconds"] = dict(self.cpu_seconds)
        return out


def manifest_entry(marker: Mapping[str, Any]) -> dict[str, Any]:
    """The dataset manifest's entry of a scene, from its written marker."""
    return {k: marker[k] for k in MANIFEST_ENTRY_KEYS if k in marker}


def stage_timings(marker_or_entry: Mapping[str, Any]) -> StageTimings:
    """The stage timings of a written marker or manifest entry."""
    return StageTimings.from_json(marker_or_entry.get("seconds"))
