"""Table and reading of the household-sparse change applied to every generator (plan.md beside this file).

    python experiments/generators-hs-2026-11-28/table.py

Rows: the household-sparse datasets of ASSIST-3D (arm A of ../holodeck-why-2026-11-28/, its per_seed/),
mesh-sampled and RandomRooms-style (per_seed/GEN-household-sparse-seedK.json here, each a probe seed's
result.json), then the three generators' default presets, seeds 0-5 (../fidelity-ema-2026-11-27/per_seed/).
Every hybrid figure is without the plane refit (hybrid-eval-dev-*-r0.json here and in holodeck-why), as
arm A's were made. Then the plan's readings, fixed before the runs, and scene0451_01
(hybrid-eval-s0451-*.json here).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
WHY = HERE.parent / "holodeck-why-2026-11-28"
sys.path.insert(0, str(WHY))
from table import EMA, print_s0451, print_table, s0451_per_seed  # noqa: E402  (holodeck-why's reader and table of per-seed files)

ASSIST = "ASSIST-3D, household-sparse"
ROWS = [(ASSIST, WHY / "per_seed", "assist3d-household-sparse", 3),
        ("mesh-sampled, household-sparse", HERE / "per_seed", "mesh-sampled-household-sparse", 3),
        ("RandomRooms-style, household-sparse", HERE / "per_seed", "randomrooms-household-sparse", 3),
        ("ASSIST-3D (preset)", EMA, "assist3d", 6),
        ("mesh-sampled (preset)", EMA, "mesh-sampled", 6),
        ("RandomRooms-style (preset)", EMA, "randomrooms", 6)]
BASELINES = [("mesh-sampled, household-sparse", "mesh-sampled (preset)"),
             ("RandomRooms-style, household-sparse", "RandomRooms-style (preset)")]


def main() -> None:
    table = print_table(ROWS, hybrid_dirs=(WHY, HERE))
    print()
    if (ASSIST, "learned") not in table:
        raise SystemExit(f"{ASSIST}: no seeds found in {WHY / 'per_seed'}")
    ra, rowa = table[(ASSIST, "learned")]
    for name, preset in BASELINES:
        if (name, "learned") not in table or len(table[(name, "learned")][0]) < 3:
            n = len(table[(name, "learned")][0]) if (name, "learned") in table else 0
            print(f"reading against {name}: pending ({n} of 3 seeds; the plan reads all three)")
            continue
        rb, rowb = table[(name, "learned")]
        gap = rowa["AP50"][0] - rowb["AP50"][0]
        sd = max(rowa["AP50"][1], rowb["AP50"][1])
        ahead = sum(a["AP50"] > b["AP50"] for a, b in zip(sorted(ra, key=lambda r: r["seed"]),
                                                            sorted(rb, key=lambda r: r["seed"])))
        verdict = "ASSIST-3D leads it with the household-sparse change" if gap > sd else "not met against it"
        print(f"reading against {name} (plan.md): learned dev AP50 {rowa['AP50'][0]:.3f} vs {rowb['AP50'][0]:.3f}, "
              f"gap {gap:+.3f} against the larger std {sd:.3f}, ahead in {ahead} of {len(rb)} paired seeds: {verdict}")
        if (preset, "learned") in table:
            rp, rowp = table[(preset, "learned")]
            print(f"  the change on {name.split(',')[0]} itself: {rowb['AP50'][0]:.3f} ± {rowb['AP50'][1]:.3f} "
                  f"({len(rb)} seeds) against its preset's {rowp['AP50'][0]:.3f} ± {rowp['AP50'][1]:.3f} ({len(rp)})")
    s0451()


def s0451() -> None:
    """scene0451_01 per generator and seed, then plan.md's amendment 2 reading once ASSIST-3D has 3 seeds."""
    files = sorted(HERE.glob("hybrid-eval-s0451-*.json")) + [WHY / "hybrid-eval-s0451-part2-A2-r0.json"]
    per = s0451_per_seed(files)
    print_s0451(per, show_seeds=True)
    a = "assist3d-household-sparse"
    for part in ("learned", "hybrid"):
        seeds_a = per.get((a, part), {})
        if len(seeds_a) < 3:
            print(f"scene0451_01 reading ({part}): pending ({len(seeds_a)} of 3 ASSIST-3D seeds; plan.md, amendment 2)")
            continue
        va = np.array(list(seeds_a.values()))
        for x in ("mesh-sampled-household-sparse", "randomrooms-household-sparse"):
            vx = np.array(list(per.get((x, part), {}).values()))
            if len(vx) < 3:
                print(f"scene0451_01 reading ({part}) against {x}: pending ({len(vx)} of 3 seeds)")
                continue
            gap, sd = va.mean() - vx.mean(), max(va.std(ddof=1), vx.std(ddof=1))
            verdict = "confirmed on scene0451_01" if gap > sd else "not confirmed"
            print(f"scene0451_01 reading ({part}{', the plan reads this row' if part == 'learned' else ', beside it'}) "
                  f"against {x}: {va.mean():.3f} vs {vx.mean():.3f}, gap {gap:+.3f} against the larger std {sd:.3f}: {verdict}")

if __name__ == "__main__":
    main()
