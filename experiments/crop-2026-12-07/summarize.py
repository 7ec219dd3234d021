"""The crop comparison (plan.md's reading): the 4.5 m crop's seeds against the scaling study's 2,000:250 point.

    python experiments/crop-2026-12-07/summarize.py [--copy OUT]

``--copy OUT`` first copies each finished seed's result.json from OUT/probe-crop45-s250-t2000/seed_K/ into per_seed/.
Figures as in the scaling study (experiments/scaling-2026-12-05/summarize.py, whose helpers this imports): AP50 per
scan, a room the mean of its scans, a seed's figure the mean over the 6 rooms. One seed decides nothing.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import shutil
import statistics
from pathlib import Path

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("scaling_summary", HERE.parent / "scaling-2026-12-05" / "summarize.py")
scaling = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(scaling)


def seeds_of(folder: Path, pattern: str) -> dict[int, dict]:
    return {int(p.stem.rsplit("_", 1)[1]): json.loads(p.read_text()) for p in sorted(folder.glob(pattern))}


def figure(seeds: dict[int, dict], kind: str) -> tuple[float, float, list[float], dict[str, float]]:
    per_seed, rooms = [], {}
    for k in sorted(seeds):
        res = seeds[k] if kind == "learned" else seeds[k]["hybrid"]
        rm = scaling.room_means(res["per_scene"])
        per_seed.append(sum(rm.values()) / len(rm))
        for r, v in rm.items():
            rooms.setdefault(r, []).append(v)
    sd = statistics.stdev(per_seed) if len(per_seed) > 1 else float("nan")
    return statistics.fmean(per_seed), sd, per_seed, {r: statistics.fmean(v) for r, v in rooms.items()}


def copy_seeds(run: Path, pattern: str, folder: Path, prefix: str) -> None:
    """Copy each finished seed's ``run/<pattern>`` (.../seed_K/result.json) to folder/<prefix>-seed_K.json."""
    folder.mkdir(exist_ok=True)
    for res in sorted(run.glob(pattern)):
        dest = folder / f"{prefix}-{res.parent.name}.json"
        if not dest.exists():
            shutil.copyfile(res, dest)
            print(f"copied {dest.name}")


def print_table(arms: dict[str, dict[int, dict]]) -> dict[str, tuple[float, float, int, dict[str, float]]]:
    """The arms' table (learned and hybrid, per seed and per room); per arm with seeds (mean, spread, seeds, rooms)."""
    print("| arm | seeds | learned AP50, 6-room mean (per seed) | hybrid AP50 | learned per room |")
    print("| --- | ---: | --- | --- | --- |")
    figs = {}
    for name, seeds in arms.items():
        if not seeds:
            print(f"| {name} | 0 | not run yet | | |")
            continue
        lm, ls, lv, lr = figure(seeds, "learned")
        hm, hs, hv, _ = figure(seeds, "hybrid")
        figs[name] = (lm, ls, len(seeds), lr)
        spread = f" ± {ls:.3f}" if len(seeds) > 1 else " (one seed)"
        print(f"| {name} | {len(seeds)} | {lm:.3f}{spread} ({', '.join(f'{x:.3f}' for x in lv)}) | {hm:.3f} "
              f"({', '.join(f'{x:.3f}' for x in hv)}) | {', '.join(f'{r} {v:.3f}' for r, v in lr.items())} |")
    return figs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--copy", type=Path, help="the run folder to copy finished seeds from")
    ap.add_argument("--decide", action="store_true",
                    help="exit 0 only if plan.md's AP criterion holds (two seeds, level with 6 m), else 1")
    a = ap.parse_args()
    (HERE / "per_seed").mkdir(exist_ok=True)
    if a.copy:
        copy_seeds(a.copy, "probe-crop45-s250-t2000/seed_*/result.json", HERE / "per_seed", "crop45-s250-t2000")
    arms = {"6 m crop (scaling 2,000:250)": seeds_of(HERE.parent / "scaling-2026-12-05" / "per_seed",
                                                     "probe-s250-t2000-seed_*.json"),
            "4.5 m crop": seeds_of(HERE / "per_seed", "crop45-s250-t2000-seed_*.json")}
    figs = print_table(arms)
    crop = figs.get("4.5 m crop")
    base = figs["6 m crop (scaling 2,000:250)"]
    if crop is None or crop[2] < 2:
        print("\nThe 4.5 m crop has fewer than 2 seeds: by plan.md this decides nothing.")
        raise SystemExit(1 if a.decide else 0)
    margin = max(base[1], crop[1])
    level = crop[0] >= base[0] - margin
    print(f"\n4.5 m {crop[0]:.3f} against 6 m {base[0]:.3f} (difference {crop[0] - base[0]:+.3f}, margin {margin:.3f}): "
          + ("not below by more than the margin: AP is level; adopt if the bench check holds (plan.md)"
             if level else "below by more than the margin: 6 m stays"))
    if a.decide:
        raise SystemExit(0 if level else 1)


if __name__ == "__main__":
    main()
