"""The depth-first placement search shared by the floor, wall and on-top groups.

A *problem* supplies, for object ``k`` of the plan and the objects placed so far, a short list of
valid candidate poses ordered best first (``candidates``), and applies/undoes a choice
(``push``/``pop``). The search walks the tree whose node at depth ``k`` has the children
``candidate_1, ..., candidate_m, SKIP``: the first descent is the greedy layout (each object at
its best valid pose, skipped with a reason when none is valid). Every leaf is a complete layout;
the one with the fewest avoidable skips wins (= the most objects).

Branch and bound: once a layout with ``S`` skips is known, any node whose path already holds
``S`` skips (plus the skips the problem can prove are coming) is cut. Backtracking therefore
returns straight to the objects placed just before the last skipped object and repositions them
(the paper's "backtrack to reposition the previous object"), then tries the skipped object
again. Such a backtrack is a *probe* for the next object the best layout skipped: if that object
still finds no place, the branch is abandoned at once instead of re-evaluating every later
object (conflict-directed; this makes each backtrack cost a few nodes). An object that cannot be
placed even in the empty scene is dropped up front and never causes backtracking.

Bounds, all deterministic except the wall-clock safety net: ``max_backtracks`` alternatives in
all, ``patience`` alternatives without an improvement, ``max_nodes`` candidate evaluations (the
greedy first descent always completes), and ``budget_s`` seconds as a safety net only.
"""

from __future__ import annotations

import bisect
import math
import time
from dataclasses import dataclass, field
from typing import Protocol

__all__ = ["Choice", "SearchProblem", "SearchResult", "depth_first"]


@dataclass(frozen=True)
class Choice:
    """One candidate pose and its soft-relation score in [0, 1]."""

    x: float
    y: float
    yaw: float
    z: float
    score: float


class SearchProblem(Protocol):
    n: int

    def candidates(self, k: int) -> tuple[list[Choice], str]:
        """Valid choices for object ``k`` in the current state, best first (at most the branch
        limit), and the reason when there is none."""
        ...

    def push(self, k: int, choice: Choice) -> None: ...

    def pop(self, k: int) -> None: ...

    def unavoidable(self, k: int) -> str | None:
        """A reason if object ``k`` can never be placed whatever else is placed, else None."""
        ...

    def min_future_skips(self, k: int, placed: int) -> int:
        """A lower bound on the skips still to come among objects ``k..n-1`` with ``placed``
        objects placed (e.g. a capacity limit)."""
        ...


@dataclass
class SearchResult:
    choices: list[Choice | None]  # per object; None = dropped
    reasons: list[str | None]  # per object: why it was dropped
    score: float  # mean score of the placed objects
    stats: dict = field(default_factory=dict)


@dataclass
class _Frame:
    cands: list[Choice]
    reason: str
    cost: int  # 1 for an avoidable skip, 0 for a forced one
    next: int = 0
    skip_done: bool = False
    taken: Choice | None = None
    skipped_here: bool = False
    prev_probe: int | None = None


def depth_first(problem: SearchProblem, *, max_backtracks: int, patience: int, budget_s: float,
                max_nodes: int | None = None) -> SearchResult:
    """Run the bounded depth-first search; always returns a complete layout (the best found)."""
    t0 = time.perf_counter()
    n = problem.n
    forced = [problem.unavoidable(k) for k in range(n)]
    frames: list[_Frame] = []
    skipped = 0
    placed = 0
    best: tuple[list[Choice | None], list[str | None]] | None = None
    best_skipped = math.inf
    nodes = backtracks = since_best = solutions = 0
    stop_reason = "exhausted"
    depth = 0
    best_skips: list[int] = []  # depths where the best layout skipped an object it could have placed
    probe: int | None = None  # the skipped object the current backtrack tries to make room for

    def record() -> None:
        nonlocal best, best_skipped, since_best, solutions, best_skips
        best_skips = [d for d, f in enumerate(frames) if f.skipped_here and f.cost]
        choices = [f.taken if not f.skipped_here else None for f in frames]
        reasons = [f.reason if f.skipped_here else None for f in frames]
        best = (choices, reasons)
        best_skipped = skipped
        since_best = 0
        solutions += 1

    def next_skip(d: int) -> int | None:
        i = bisect.bisect_right(best_skips, d)
        return best_skips[i] if i < len(best_skips) else None

    def undo(f: _Frame) -> None:
        nonlocal skipped, placed, probe
        probe = f.prev_probe
        if f.taken is not None:
            problem.pop(len(frames) - 1)
            placed -= 1
            f.taken = None
        elif f.skipped_here:
            skipped -= f.cost
            f.skipped_here = False

    while True:
        if depth == n:
            record()
            if best_skipped == 0:
                stop_reason = "optimal"
                break
            depth -= 1
            undo(frames[depth])
            continue
        if len(frames) == depth:
            if best is not None and skipped + problem.min_future_skips(depth, placed) >= best_skipped:
                frames.append(_Frame([], "pruned", 1, skip_done=True))
            elif forced[depth] is not None:
                frames.append(_Frame([], forced[depth] or "", 0))
            else:
                cands, reason = problem.candidates(depth)
                nodes += 1
                frames.append(_Frame(cands, reason, 1))
        f = frames[depth]
        if f.next < len(f.cands):
            if f.next > 0:
                backtracks += 1
                since_best += 1
                if backtracks > max_backtracks or since_best > patience:
                    stop_reason = "backtracks" if backtracks > max_backtracks else "patience"
                    break
                if max_nodes is not None and nodes >= max_nodes:
                    stop_reason = "nodes"
                    break
                if time.perf_counter() - t0 > budget_s:
                    stop_reason = "budget"
                    break
            choice = f.cands[f.next]
            f.prev_probe = probe
            if f.next > 0:
                probe = next_skip(depth)
            elif depth == probe:
                probe = None  # the object the backtrack made room for fits now
            f.next += 1
            problem.push(depth, choice)
            placed += 1
            f.taken = choice
            depth += 1
            continue
        if not f.skip_done:
            f.skip_done = True
            if skipped + f.cost < best_skipped and not (f.cost and depth == probe):
                f.prev_probe = probe
                if f.cands:
                    probe = next_skip(depth)
                skipped += f.cost
                f.skipped_here = True
                depth += 1
                continue
        # exhausted: go up
        frames.pop()
        depth -= 1
        if depth < 0:
            break
        undo(frames[depth])
        if best is None and time.perf_counter() - t0 > budget_s:
            stop_reason = "budget"
            break

    if best is None:
        # Budget ran out before the first complete layout: keep the current path, drop the rest.
        choices = [f.taken for f in frames[:depth]]
        reasons: list[str | None] = [None if c is not None else f.reason for f, c in zip(frames, choices)]
        choices += [None] * (n - len(choices))
        reasons += ["search budget exhausted before this object was tried"] * (n - len(reasons))
        best = (choices, reasons)
    choices, reasons = best
    kept = [c.score for c in choices if c is not None]
    stats = {"nodes": nodes, "backtracks": backtracks, "solutions": solutions, "stop": stop_reason,
             "budget_hit": stop_reason == "budget", "seconds": time.perf_counter() - t0}
    return SearchResult(list(choices), list(reasons), float(sum(kept) / len(kept)) if kept else 0.0, stats)
