"""plan.md's reading: learned AP50 per room with the openings filled (2,000 steps, 250 scenes, seeds 0 and 1) against
the scaling study's 2,000:250 seeds 0 and 1; hybrid, AP25 beside it. Written before any run.

    python experiments/openings2000/summarize.py [--copy OUT]

``--copy OUT`` first copies OUT/probe-s250-t2000/seed_K/result.json into per_seed/ (probe-s250-t2000-seed_K.json).
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
from pathlib import Path

from assist3d.bench.evaluation.compare import paired_comparison, room_means

HERE = Path(__file__).resolve().parent
BASE = HERE.parent / "scaling-2026-12-05" / "per_seed"
ROOMS = ("scene0006", "scene0007", "scene0008", "scene0009", "scene0010", "scene0451")
NAME = "probe-s250-t2000-seed_{}.json"


def per_room(folder: Path, kind: str, metric: str) -> tuple[dict[str, float], list[float]] | None:
    """Per room the mean over seeds 0 and 1, and each seed's 6-room mean; None until both seeds are there."""
    seeds = []
    for k in (0, 1):
        path = folder / NAME.format(k)
        if not path.exists():
            return None
        res = json.loads(path.read_text())
        per = res["per_scene"] if kind == "learned" else res["hybrid"]["per_scene"]
        seeds.append(room_means({scan: fig[metric] for scan, fig in per.items()}))
    return ({r: statistics.mean(s[r] for s in seeds) for r in ROOMS},
            [statistics.mean(s[r] for r in ROOMS) for s in seeds])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--copy", type=Path, help="the run folder to copy finished seeds from")
    a = ap.parse_args()
    if a.copy:
        (HERE / "per_seed").mkdir(exist_ok=True)
        for res in sorted(a.copy.glob("probe-s250-t2000/seed_*/result.json")):
            dest = HERE / "per_seed" / f"probe-s250-t2000-{res.parent.name}.json"
            shutil.copyfile(res, dest)
            print(f"copied {dest.name}")
    for kind, metric in (("learned", "AP50"), ("hybrid", "AP50"), ("learned", "AP25")):
        fill, base = per_room(HERE / "per_seed", kind, metric), per_room(BASE, kind, metric)
        if fill is None or base is None:
            print(f"{kind} {metric}: both seeds not finished yet")
            return
        (f_rooms, f_seeds), (b_rooms, b_seeds) = fill, base
        spread = max(statistics.stdev(f_seeds), statistics.stdev(b_seeds))
        c = paired_comparison(b_rooms, f_rooms, metric=metric)
        print(f"{kind} {metric}, 6-room mean: openings filled {statistics.mean(f_seeds):.3f} (seeds "
              f"{', '.join(f'{v:.3f}' for v in f_seeds)}), baseline {statistics.mean(b_seeds):.3f} (seeds "
              f"{', '.join(f'{v:.3f}' for v in b_seeds)}); larger seed spread {spread:.3f}")
        print("  per room, filled / baseline: " + ", ".join(f"{r} {f_rooms[r]:.3f}/{b_rooms[r]:.3f}" for r in ROOMS))
        print(f"  filled - baseline {c.mean_diff:+.3f}, 95 % interval over rooms [{c.ci95[0]:+.3f}, {c.ci95[1]:+.3f}], "
              f"higher in {c.higher}, lower in {c.lower} of 6 rooms")
        if kind == "learned" and metric == "AP50":
            if c.mean_diff > spread and c.higher >= 5:
                verdict = "adopt: fill_openings joins the assist3d preset (the model rule then decides the shipped model)"
            elif -c.mean_diff > spread and c.lower >= 5:
                verdict = "reject: the option stays off"
            else:
                verdict = "not separated: the default data stays as it is"
            print(f"  by plan.md's rule: {verdict}")


if __name__ == "__main__":
    main()
