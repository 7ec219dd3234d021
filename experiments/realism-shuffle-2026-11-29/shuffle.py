"""plan.md of this folder: the real dev scans scored as they are and with their objects thrown about.

    python experiments/realism-shuffle-2026-11-29/shuffle.py ../shared/data/real/dev [--seeds 5] [--json OUT]

Every annotated object (``array:...?objects=annotated``) of a scan is moved rigidly: a random yaw about
its centre and a random horizontal position at which all its points fall on the scan's floor plan
(10 cm cells occupied by any point of the scan, holes filled, as the realism score builds it); heights
are kept and objects may overlap (RandomRooms-style). Walls, floor and unlabelled points stay. Each room
is scored against the other four rooms' unshuffled statistics, as ``scripts/realism_reference.py --loro``
scores the real rooms.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np
from scipy import ndimage

from assist3d.data import open_dataset
from assist3d.bench.metrics.realism import CELL, RealismReference, RealismStats, realism_score, scene_stats

TRIES = 200


def floor_plan(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Occupied 10 cm cells of the scan, closed and hole-filled; (mask, origin)."""
    c = np.floor(xy / CELL).astype(np.int64)
    lo = c.min(0)
    c -= lo
    plan = np.zeros(tuple(c.max(0) + 1), bool)
    plan[c[:, 0], c[:, 1]] = True
    plan = ndimage.binary_fill_holes(ndimage.binary_closing(plan, iterations=2) | plan)
    return plan, lo


def on_plan(xy: np.ndarray, plan: np.ndarray, lo: np.ndarray) -> bool:
    c = np.floor(xy / CELL).astype(np.int64) - lo
    inside = (c >= 0).all(1) & (c[:, 0] < plan.shape[0]) & (c[:, 1] < plan.shape[1])
    return bool(inside.all() and plan[c[:, 0], c[:, 1]].all())


def shuffled(coord: np.ndarray, instance: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, int]:
    """The scan with every object moved (see the module docstring); also how many found no place."""
    out = coord.copy()
    plan, lo = floor_plan(coord[:, :2])
    cells = np.argwhere(plan)
    stuck = 0
    for o in np.unique(instance[instance >= 0]):
        m = instance == o
        xy = coord[m, :2]
        centre = xy.mean(0)
        for _ in range(TRIES):
            a = rng.uniform(0.0, 2.0 * np.pi)
            rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
            to = (cells[rng.integers(len(cells))] + lo + rng.uniform(0, 1, 2)) * CELL
            moved = (xy - centre) @ rot.T + to
            if on_plan(moved, plan, lo):
                out[m, :2] = moved
                break
        else:
            stuck += 1  # left where it was
    return out, stuck


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dev", help="folder of (N, 8) .npy real scans")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    ds = open_dataset(f"array:{args.dev}?objects=annotated")
    scans = {sid: ds.load(sid) for sid in ds.scene_ids}
    real = {sid: scene_stats(s.coord.astype(np.float64), s.instance) for sid, s in scans.items()}
    rooms = sorted({sid[:9] for sid in scans})
    report: dict = {"seeds": args.seeds, "rooms": {}}
    for r in rooms:
        rest = RealismStats()
        for sid, st in real.items():
            if sid[:9] != r:
                rest.add(st)
        ref = RealismReference.from_stats(rest, f"rooms other than {r}")
        held = RealismStats()
        for sid, st in real.items():
            if sid[:9] == r:
                held.add(st)
        scores, stuck = [], 0
        for seed in range(args.seeds):
            rng = np.random.default_rng([seed, int(r[5:9])])
            shuf = RealismStats()
            for sid, s in scans.items():
                if sid[:9] == r:
                    moved, k = shuffled(s.coord.astype(np.float64), s.instance, rng)
                    stuck += k
                    shuf.add(scene_stats(moved, s.instance))
            scores.append(realism_score(shuf, ref)[0])
        report["rooms"][r] = {"real": realism_score(held, ref)[0], "shuffled_mean": round(float(np.mean(scores)), 2),
                              "shuffled_std": round(float(np.std(scores)), 2), "shuffled": scores,
                              "objects": held.objects, "objects_left_in_place": stuck}
        v = report["rooms"][r]
        print(f"{r}: real {v['real']}, shuffled {v['shuffled_mean']} +- {v['shuffled_std']} "
              f"({v['objects']} objects; {stuck} of {v['objects'] * args.seeds} moves found no place)", flush=True)
    rr = report["rooms"].values()
    report["mean_real"] = round(float(np.mean([v["real"] for v in rr])), 2)
    report["mean_shuffled"] = round(float(np.mean([v["shuffled_mean"] for v in rr])), 2)
    print(f"mean over rooms: real {report['mean_real']}, shuffled {report['mean_shuffled']}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
