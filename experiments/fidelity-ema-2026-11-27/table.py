"""Table of the generator comparison with today's defaults from the committed per-seed results
(per_seed/GENERATOR-seedK.json, each a probe seed's result.json), and the issue's target check.

    python experiments/fidelity-ema-2026-11-27/table.py [--seeds K]

Only seeds 0..K-1 are used (default 3, the published verdict of the plan; ``--seeds 6`` for the
verdict at six seeds that the plan's amendment fixed in advance).

Then, from hybrid-eval-s0451-*.json (metrics only) (``scripts/hybrid_eval.py`` over the same models with
``--eval array:../shared/data/real/scannet_scene0451_01.npy``), the same models on that scan.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from assist3d.bench.evaluation.compare import room_of

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1] / "scripts"))
from fidelity_table import row_from_runs  # noqa: E402  (the per-room and mean/std rows of fidelity.sh's table)
NAMES = {"assist3d": "ASSIST-3D", "randomrooms": "RandomRooms-style", "mesh-sampled": "mesh-sampled",
         "holodeck-style": "Holodeck-style", "no-context": "no-context"}


def runs(gen: str, part: str, max_seeds: int) -> list[dict]:
    out = []
    numbered = ((int(f.stem.rsplit("seed", 1)[1]), f) for f in HERE.glob(f"per_seed/{gen}-seed*.json"))
    files = [f for k, f in sorted(numbered) if k < max_seeds]
    for f in files:
        r = json.loads(f.read_text())
        out.append(r if part == "learned" else r["hybrid"])
    return out


def main(max_seeds: int = 3) -> None:
    gens = [g for g in NAMES if list(HERE.glob(f"per_seed/{g}-seed*.json"))]
    rooms = sorted({room_of(sid) for g in gens for r in runs(g, "learned", max_seeds) for sid in r["per_scene"]})
    print("AP50 per seed is pooled over the 10 scans; the room columns are means of per-scan AP50 (over the "
          "room's scans and the seeds), so they do not average to it.\n")
    print("| training data | inference | seeds | AP50 mean ± std | AP50 per seed | AP25 mean | "
          + " | ".join(f"AP50 {r}" for r in rooms) + " |")
    print("|---|---|---:|---:|---|---:|" + "---:|" * len(rooms))
    stats: dict = {}
    for part in ("learned", "hybrid"):
        for g in gens:
            rs = runs(g, part, max_seeds)
            a50 = np.array([r["AP50"] for r in rs])
            seeds = [r["seed"] for r in rs]
            row = row_from_runs(NAMES[g], rs)
            sd = row["AP50"][1] if len(a50) > 1 else float("nan")
            stats[(g, part)] = (a50, sd, seeds)
            print(f"| {NAMES[g]} | {part} | {len(rs)} | {row['AP50'][0]:.3f} ± {sd:.3f} | "
                  + " / ".join(f"{x:.3f}" for x in a50) + f" | {row['AP25'][0]:.3f} | "
                  + " | ".join(f"{row['rooms'][k]:.3f}" for k in rooms) + " |")
    print()
    target_lines(stats)
    scene0451(max_seeds)


def target_lines(stats: dict) -> None:
    """The issue's target test, ASSIST-3D against mesh-sampled and RandomRooms-style: ``stats`` maps
    (generator, part) to (AP50 per seed, sample std, seed ids)."""
    for part in ("learned", "hybrid"):
        a, sa, seeds_a = stats[("assist3d", part)]
        for other in ("mesh-sampled", "randomrooms"):
            if (other, part) not in stats:
                continue
            b, sb, seeds_b = stats[(other, part)]
            common = sorted(set(seeds_a) & set(seeds_b))
            pa = np.array([a[seeds_a.index(k)] for k in common])
            pb = np.array([b[seeds_b.index(k)] for k in common])
            n = len(common)
            gap = a.mean() - b.mean()
            big = max(sa, sb)
            ahead = int((pa > pb).sum())
            paired = float((pa - pb).mean()) if n else float("nan")
            verdict = ("pending (fewer than 3 seeds)" if min(len(a), len(b)) < 3
                       else "met" if gap > big else "not met")
            print(f"{part}: ASSIST-3D vs {NAMES[other]}: gap of means {gap:+.3f}, paired gap {paired:+.3f}, larger std "
                  f"{big:.3f}, ahead in {ahead} of {n} "
                  f"paired seeds, seeds {len(a)}/{len(b)}: target {verdict}")


def scene0451(max_seeds: int) -> None:
    """AP50 on scene0451_01 per generator (learned and hybrid rows of hybrid_eval.py), seeds in order."""
    files = sorted(HERE.glob("hybrid-eval-s0451-*.json"))
    if not files:
        return
    per: dict[tuple[str, str], dict[int, float]] = {}
    control = None
    for f in files:
        d = json.loads(f.read_text())
        if len(d["eval"]) != 1 or "scene0451_01" not in d["eval"][0]:
            raise SystemExit(f"{f}: expected one --eval spec, scannet_scene0451_01, not {d['eval']}")
        if control is not None and d["control"] != control:
            raise SystemExit(f"{f}: its geometric reference differs from the other files'")
        control = d["control"]
        for path, rows in d["models"].items():
            parts = Path(path).parts  # .../probe/GENERATOR/seed_K/model.pt
            gen, seed = parts[-3], int(parts[-2].removeprefix("seed_"))
            if gen not in NAMES:
                raise SystemExit(f"{f}: {path}: generator {gen!r} is not one of {list(NAMES)}")
            if seed >= max_seeds:
                continue
            for part in ("learned", "hybrid"):
                seeds = per.setdefault((gen, part), {})
                if seed in seeds:
                    raise SystemExit(f"{f}: {gen} seed {seed} is also in another file")
                seeds[seed] = rows[part][0]["AP50"]  # the first (only) --eval spec
    print("\nscene0451_01 (one scan, not in the dev set), AP50; geometric reference "
          f"{control['geometric'][0]['AP50']:.3f}:\n")
    print("| training data | inference | seeds | AP50 mean ± std | AP50 per seed |")
    print("|---|---|---:|---:|---|")
    stats: dict = {}
    for part in ("learned", "hybrid"):
        for g in NAMES:
            if (g, part) not in per:
                continue
            seeds = sorted(per[(g, part)])
            v = np.array([per[(g, part)][k] for k in seeds])
            sd = v.std(ddof=1) if len(v) > 1 else float("nan")
            stats[(g, part)] = (v, sd, seeds)
            print(f"| {NAMES[g]} | {part} | {len(v)} | {v.mean():.3f} ± {sd:.3f} | "
                  + " / ".join(f"{x:.3f}" for x in v) + " |")
    print()
    target_lines(stats)

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=3, help="use seeds 0..K-1 (default 3)")
    main(ap.parse_args().seeds)
