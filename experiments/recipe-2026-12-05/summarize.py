"""The recipe comparison of plan.md, read by its rules (section "Reading", fixed before the runs).

    python experiments/recipe-2026-12-05/summarize.py [--copy OUT] [--scaling-run SCALING_OUT]

``--copy OUT`` first copies every finished seed of run.sh's folder OUT into ``per_seed/`` (the per-scan
figures are all the reading needs; models and data stay outside the repository). ``--scaling-run``: the
scaling study's run folder, whose ``probe-s250-t200/seed_{0,1}`` are the synth arm's seeds 0 and 1 (the same
command, plan.md); copied the same way.

Figure: the network's instances alone (learned AP50) per dev scan. An arm's seed k is complete when every
fold of that seed has finished (the synth arm: one run covers every dev scan). A room's figure is the mean
of its scans; an arm's figure per room the mean over its complete seeds; the 5-room mean per seed gives
the seed spread. "A beats B": the mean over rooms of A - B exceeds the larger of the two arms' seed
spreads and A is ahead in at least 4 of the 5 rooms; otherwise "not separated". The 95 % intervals
resample rooms (the per-scan means over seeds, as ``scripts/compare_probes.py``) and, in the second one,
each arm's seeds too. Each arm uses all of its complete seeds (the plan fixes 3 each); a comparison with
an arm of fewer seeds is marked provisional.
"""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path

from assist3d.bench.evaluation.compare import recipe_comparison, room_means

HERE = Path(__file__).resolve().parent
ARMS = ("real", "synth", "mix-assist3d", "mix-randomrooms")
LABEL = {"real": "real only", "synth": "synthetic only (ASSIST-3D)", "mix-assist3d": "real + 0.5 x ASSIST-3D",
         "mix-randomrooms": "real + 0.5 x RandomRooms-style"}
ROOMS = ("scene0006", "scene0007", "scene0008", "scene0009", "scene0010")
# the pairs the plan reports; the first is issue 51's target
PAIRS = (("mix-assist3d", "real"), ("mix-assist3d", "synth"), ("mix-assist3d", "mix-randomrooms"),
         ("synth", "real"), ("mix-randomrooms", "real"))


def copy_from(out: Path | None, scaling: Path | None) -> None:
    dest = HERE / "per_seed"
    runs = [] if out is None else sorted(out.glob("*/*/seed_*/result.json")) + sorted(out.glob("synth/seed_*/result.json"))
    for res in runs:
        rel = res.relative_to(out)
        name = "-".join(rel.parts[:-1]) + ".json"  # e.g. real-scene0006-seed_0.json, synth-seed_2.json
        if not (dest / name).exists():
            dest.mkdir(exist_ok=True)
            per_scene = json.loads(res.read_text())["per_scene"]
            (dest / name).write_text(json.dumps({"per_scene": per_scene}, indent=1) + "\n")
            print(f"copied {name}")
    if scaling is not None:
        for k in (0, 1):
            res = scaling / "probe-s250-t200" / f"seed_{k}" / "result.json"
            name = f"synth-seed_{k}.json"
            if res.exists() and not (dest / name).exists():
                per_scene = {s: v for s, v in json.loads(res.read_text())["per_scene"].items() if s[:9] in ROOMS}
                (dest / name).write_text(json.dumps({"per_scene": per_scene}, indent=1) + "\n")
                print(f"copied {name} (the scaling study's 200-step run)")


def load() -> dict[str, dict[int, dict[str, float]]]:
    """arm -> complete seed -> per-scan learned AP50 over the 10 dev scans."""
    files = {p.stem: json.loads(p.read_text())["per_scene"] for p in sorted((HERE / "per_seed").glob("*.json"))}
    arms: dict[str, dict[int, dict[str, float]]] = {}
    for arm in ARMS:
        for k in range(10):
            if arm == "synth":
                got = files.get(f"synth-seed_{k}")
                scans = {s: v["AP50"] for s, v in got.items()} if got else None
            else:
                folds = [files.get(f"{arm}-{room}-seed_{k}") for room in ROOMS]
                scans = ({s: v["AP50"] for f in folds for s, v in f.items()} if all(folds) else None)
            if scans:
                arms.setdefault(arm, {})[k] = scans
    return arms


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--copy", type=Path, help="run.sh's OUT folder to copy finished seeds from")
    ap.add_argument("--scaling-run", type=Path, help="the scaling study's run folder (synth seeds 0 and 1)")
    a = ap.parse_args()
    copy_from(a.copy, a.scaling_run)
    arms = load()
    stats = {}
    print("| arm | seeds | " + " | ".join(ROOMS) + " | 5-room mean ± seed spread (per seed) |")
    print("| --- | ---: | " + " | ".join("---:" for _ in ROOMS) + " | --- |")
    for arm in ARMS:
        seeds = arms.get(arm, {})
        if not seeds:
            print(f"| {LABEL[arm]} | 0 | " + " | ".join("" for _ in ROOMS) + " | not run yet |")
            continue
        per_seed_rooms = [room_means(s) for s in seeds.values()]
        rooms = {r: statistics.fmean(p[r] for p in per_seed_rooms) for r in ROOMS}
        five = [statistics.fmean(p.values()) for p in per_seed_rooms]
        sd = statistics.stdev(five) if len(five) > 1 else float("nan")
        stats[arm] = (rooms, statistics.fmean(five), sd)
        print(f"| {LABEL[arm]} | {len(seeds)} | " + " | ".join(f"{rooms[r]:.3f}" for r in ROOMS)
              + f" | {statistics.fmean(five):.3f} ± {sd:.3f} ({', '.join(f'{x:.3f}' for x in five)}) |")
    print()
    for x, y in PAIRS:
        if x not in stats or y not in stats:
            print(f"- {LABEL[x]} against {LABEL[y]}: not both run yet")
            continue
        (rx, _, sx), (ry, _, sy) = stats[x], stats[y]
        diff = {r: rx[r] - ry[r] for r in ROOMS}
        mean_diff = statistics.fmean(diff.values())
        ahead = sum(d > 0 for d in diff.values())
        spread = max(sx, sy)
        c = recipe_comparison(list(arms[y].values()), list(arms[x].values()))  # x - y
        few = min(len(arms[x]), len(arms[y])) < 3
        verdict = ("BEATS" if mean_diff > spread and ahead >= 4 else
                   "is beaten by" if -mean_diff > spread and ahead <= 1 else "is not separated from")
        print(f"- {LABEL[x]} {verdict} {LABEL[y]}: mean over rooms {mean_diff:+.3f} (larger seed spread "
              f"{spread:.3f}), ahead in {ahead} of 5 rooms ("
              + ", ".join(f"{r} {d:+.3f}" for r, d in diff.items())
              + f"); per-scan mean difference {c.paired.mean_diff:+.3f}, 95 % interval over rooms "
              f"[{c.paired.ci95[0]:+.3f}, {c.paired.ci95[1]:+.3f}], rooms and seeds [{c.ci95[0]:+.3f}, {c.ci95[1]:+.3f}]"
              + (" (fewer than the plan's 3 seeds: provisional)" if few else ""))


if __name__ == "__main__":
    main()
