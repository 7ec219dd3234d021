"""The reading of plan.md: real + 0.5 x ASSIST-3D (two folds, one seed) against synthetic alone (the scaling
study's 2,000:250 seeds 0 and 1), learned AP50 per held-out room; hybrid beside it.

    python experiments/recipe2000-2026-12-07/summarize.py [--copy OUT]

``--copy OUT`` first copies OUT/mix-{A,B}/seed_K/result.json into per_seed/ (mix-A-seed_K.json, ...).
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
from pathlib import Path

from assist3d.bench.evaluation.compare import paired_comparison, room_means

HERE = Path(__file__).resolve().parent
SYNTH = HERE.parent / "scaling-2026-12-05" / "per_seed"
ROOMS = ("scene0006", "scene0007", "scene0008", "scene0009", "scene0010", "scene0451")


def rooms(per_scene: dict) -> dict[str, float]:
    """AP50 per room (the mean of its scans) of a probe's ``per_scene``."""
    return room_means({scan: fig["AP50"] for scan, fig in per_scene.items()})


def mix_rooms(kind: str) -> dict[str, float]:
    """Per room: the mean of its scans in the fold that held it out; scene0451 the mean of both folds' figures."""
    got: dict[str, list[float]] = {}
    for fold in ("A", "B"):
        res = json.loads((HERE / "per_seed" / f"mix-{fold}-seed_0.json").read_text())
        per = res["per_scene"] if kind == "learned" else res["hybrid"]["per_scene"]
        for room, fig in rooms(per).items():
            got.setdefault(room, []).append(fig)
    return {r: statistics.mean(v) for r, v in got.items()}


def synth_rooms(kind: str) -> tuple[dict[str, float], float]:
    """Per room the mean over seeds 0 and 1; and the seed spread (std of the seeds' 6-room means)."""
    per_seed = []
    for k in (0, 1):
        res = json.loads((SYNTH / f"probe-s250-t2000-seed_{k}.json").read_text())
        per = res["per_scene"] if kind == "learned" else res["hybrid"]["per_scene"]
        per_seed.append(rooms(per))
    spread = statistics.stdev([statistics.mean(s[r] for r in ROOMS) for s in per_seed])
    return {r: statistics.mean(s[r] for s in per_seed) for r in ROOMS}, spread


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--copy", type=Path, help="the run folder to copy finished seeds from")
    a = ap.parse_args()
    if a.copy:
        (HERE / "per_seed").mkdir(exist_ok=True)
        for res in sorted(a.copy.glob("mix-*/seed_*/result.json")):
            dest = HERE / "per_seed" / f"{res.parent.parent.name}-{res.parent.name}.json"
            shutil.copyfile(res, dest)
            print(f"copied {dest.name}")
    for kind in ("learned", "hybrid"):
        mix = mix_rooms(kind)
        synth, spread = synth_rooms(kind)
        # one figure a room on each side, so the rooms are what the bootstrap resamples and each weighs the same
        c = paired_comparison({r: synth[r] for r in ROOMS}, {r: mix[r] for r in ROOMS})
        d, (lo, hi), ahead, behind = c.mean_diff, c.ci95, c.higher, c.lower
        print(f"{kind} AP50, 6-room mean: mix {statistics.mean(mix[r] for r in ROOMS):.3f} (one seed), "
              f"synth {statistics.mean(synth[r] for r in ROOMS):.3f} (seed spread {spread:.3f})")
        print("  per room, mix / synth: " + ", ".join(f"{r} {mix[r]:.3f}/{synth[r]:.3f}" for r in ROOMS))
        print(f"  mix - synth {d:+.3f}, 95 % interval over rooms [{lo:+.3f}, {hi:+.3f}]; mix ahead in {ahead}, "
              f"behind in {behind} of 6 rooms")
        if kind == "learned":
            if d > spread and ahead >= 5:
                verdict = "mix beats synth (one seed: calls for the full design before the shipped recipe changes)"
            elif -d > spread and behind >= 5:
                verdict = "synth beats mix: synthetic data alone stays the recipe"
            else:
                verdict = "not separated: synthetic data alone stays the recipe"
            print(f"  by plan.md's rule: {verdict}")


if __name__ == "__main__":
    main()
