"""Paired comparison of two models, or two recipes, on the same real scans.

A dataset-level AP50 hides which scans moved: a recipe that gains on three scans of one room and
loses on everything else can still raise the pooled figure. :func:`paired_comparison` takes one
metric per scan for each side (for a recipe, the mean over its seeds), and reports the mean
per-scan difference, how many scans each side wins, the difference per room, and a bootstrap
interval of the mean difference that resamples **rooms** with all their scans: rescans of one room
share its objects and are not independent draws (experiments/fidelity-log.md, "Every change measured on the
real scans").

That interval answers "do these models beat those on other rooms?", not "do other seeds of recipe B
beat other seeds of recipe A?": seeds of one recipe differ by as much as recipes do
(experiments/fidelity-log.md, "How many seeds a decision needs"). :func:`recipe_comparison` takes every run of
each side and resamples the runs of each side as well as the rooms, so that its interval also holds
the seed spread (with two runs a side it is still too narrow: a bootstrap of two values underrates
their spread).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import asdict, dataclass

import numpy as np

ROOM_CHARS = 9  # other names: rescans of a room share the first 9 characters (as ScanNet's scene0006_00, _01)


@dataclass(frozen=True)
class PairedComparison:
    """``mean_diff`` and ``ci95`` are of ``b - a``, averaged over scans (every scan weighs the same)."""

    metric: str
    scans: int
    rooms: int
    mean_a: float
    mean_b: float
    mean_diff: float
    higher: int  # scans where b is above a
    lower: int
    equal: int
    ci95: tuple[float, float]
    per_room: dict[str, float]

    def to_json(self) -> dict:
        out = asdict(self)
        out["ci95"] = list(self.ci95)
        return out


_SCANNET_ROOM = re.compile(r"scene\d{4}(?!\d)")


def room_of(scan_id: str, room_chars: int = ROOM_CHARS) -> str:
    """The room of a scan: the ``sceneNNNN`` part of a ScanNet name wherever it stands in the id
    (``scene0006_01`` and ``scannet_scene0451_01`` give ``scene0006`` and ``scene0451``), else the
    first ``room_chars`` characters."""
    m = _SCANNET_ROOM.search(scan_id)
    return m.group(0) if m else scan_id[:room_chars]


def room_means(per_scan: Mapping[str, float | None], room_chars: int = ROOM_CHARS) -> dict[str, float]:
    """The mean of per-scan figures (scan id -> value; None values left out) per room, rooms sorted."""
    rooms: dict[str, list[float]] = {}
    for sid, v in per_scan.items():
        if v is not None:
            rooms.setdefault(room_of(sid, room_chars), []).append(float(v))
    return {r: float(np.mean(v)) for r, v in sorted(rooms.items())}


def _rooms(scans: list[str], room_chars: int) -> tuple[list[str], list[np.ndarray]]:
    """The rooms of ``scans`` in the order of their first scan (the draws of the seeded bootstraps
    follow it) and the indices of each room's scans."""
    rooms = np.array([room_of(s, room_chars) for s in scans])
    names = list(dict.fromkeys(rooms))
    return names, [np.flatnonzero(rooms == r) for r in names]


def _interval(means: np.ndarray) -> tuple[float, float]:
    """The 2.5th and 97.5th percentiles of bootstrap ``means``, rounded to 4 digits."""
    return round(float(np.percentile(means, 2.5)), 4), round(float(np.percentile(means, 97.5)), 4)


def paired_comparison(a: Mapping[str, float], b: Mapping[str, float], *, metric: str = "AP50",
                      room_chars: int = ROOM_CHARS, draws: int = 2000, seed: int = 0) -> PairedComparison:
    """Compare per-scan figures ``a`` and ``b`` (scan id -> value); both must hold the same scans."""
    if set(a) != set(b):
        only = sorted(set(a) ^ set(b))
        raise ValueError(f"the two sides hold different scans: {', '.join(only[:5])}" + (" ..." if len(only) > 5 else ""))
    if not a:
        raise ValueError("no scans to compare")
    scans = sorted(a)
    va = np.array([float(a[s]) for s in scans])
    vb = np.array([float(b[s]) for s in scans])
    if not (np.isfinite(va).all() and np.isfinite(vb).all()):
        raise ValueError("a per-scan figure is not finite")
    diff = vb - va
    names, members = _rooms(scans, room_chars)
    rng = np.random.default_rng(seed)
    means = np.empty(draws)
    for k in range(draws):
        rows = np.concatenate([members[i] for i in rng.integers(len(names), size=len(names))])
        means[k] = diff[rows].mean()
    return PairedComparison(
        metric=metric, scans=len(scans), rooms=len(names), mean_a=round(float(va.mean()), 4),
        mean_b=round(float(vb.mean()), 4), mean_diff=round(float(diff.mean()), 4),
        higher=int((diff > 0).sum()), lower=int((diff < 0).sum()), equal=int((diff == 0).sum()),
        ci95=_interval(means),
        per_room={r: round(float(diff[m].mean()), 4) for r, m in zip(names, members)},
    )


def mean_over_runs(runs: list[Mapping[str, float]]) -> dict[str, float]:
    """Per-scan mean over several runs (seeds or models) that all hold the same scans."""
    if not runs:
        raise ValueError("no runs")
    keys = set(runs[0])
    for r in runs[1:]:
        if set(r) != keys:
            raise ValueError("the runs hold different scans")
    return {s: float(np.mean([r[s] for r in runs])) for s in sorted(keys)}


@dataclass(frozen=True)
class RecipeComparison:
    """``paired`` compares the per-scan means over each side's runs (rooms resampled); ``ci95`` is the
    interval of the same mean difference with each side's runs resampled too; ``runs_a`` and
    ``runs_b`` are each run's mean over the scans."""

    paired: PairedComparison
    ci95: tuple[float, float]
    runs_a: list[float]
    runs_b: list[float]

    def to_json(self) -> dict:
        return self.paired.to_json() | {"ci95_rooms_and_runs": list(self.ci95), "run_means_a": self.runs_a,
                                         "run_means_b": self.runs_b}


def recipe_comparison(a_runs: list[Mapping[str, float]], b_runs: list[Mapping[str, float]], *, metric: str = "AP50",
                      room_chars: int = ROOM_CHARS, draws: int = 2000, seed: int = 0,
                      paired_runs: bool = False) -> RecipeComparison:
    """Compare two recipes from their runs (each a scan id -> value mapping; all runs of both sides
    must hold the same scans): the paired comparison of their per-scan means, and a bootstrap interval
    of the mean difference ``b - a`` that resamples rooms (the same rooms for both sides) and, within
    each side, runs. ``paired_runs``: run k of both sides is the same model (e.g. two inference
    variants of the same models), so the same runs are drawn for both sides."""
    if paired_runs and len(a_runs) != len(b_runs):
        raise ValueError(f"paired runs need as many runs on both sides ({len(a_runs)} vs {len(b_runs)})")
    paired = paired_comparison(mean_over_runs(list(a_runs)), mean_over_runs(list(b_runs)), metric=metric,
                               room_chars=room_chars, draws=draws, seed=seed)
    scans = sorted(a_runs[0])  # every run holds these scans: checked by the paired comparison above
    va = np.array([[float(r[s]) for s in scans] for r in a_runs])
    vb = np.array([[float(r[s]) for s in scans] for r in b_runs])
    names, members = _rooms(scans, room_chars)
    rng = np.random.default_rng(seed)
    means = np.empty(draws)
    for k in range(draws):
        cols = np.concatenate([members[i] for i in rng.integers(len(names), size=len(names))])
        ra = rng.integers(len(va), size=len(va))
        rb = ra if paired_runs else rng.integers(len(vb), size=len(vb))
        means[k] = vb[np.ix_(rb, cols)].mean() - va[np.ix_(ra, cols)].mean()
    return RecipeComparison(
        paired=paired,
        ci95=_interval(means),
        runs_a=[round(float(x), 4) for x in va.mean(1)], runs_b=[round(float(x), 4) for x in vb.mean(1)])
