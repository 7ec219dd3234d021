"""Table and reading of part 2 of the Holodeck-style question (plan-part2.md beside this file).

    python experiments/holodeck-why-2026-11-28/table_part2.py

Rows: arm A (ASSIST-3D, household classes, sparser counts: per_seed/assist3d-household-sparse-seedK.json)
against the household arm of part 1 (per_seed/assist3d-household-seedK.json); arm B (Holodeck-style with
every model per class: per_seed/holodeck-allmodels-seedK.json) against Holodeck-style seeds 0-2 of the
generator comparison (../fidelity-ema-2026-11-27/per_seed/). Each file is a probe seed's result.json.
Then the plan's readings, fixed before the runs, and scene0451_01 (hybrid-eval-s0451-part2-*.json here).
Every hybrid figure is without the plane refit, as part 1's (table.hybrid_without_refit).
"""

from __future__ import annotations

import sys
from pathlib import Path


HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from table import EMA, print_s0451, print_table, s0451_per_seed  # noqa: E402  (part 1's reader and table of per-seed files)

ROWS = [("A: ASSIST-3D, household classes, sparser", HERE / "per_seed", "assist3d-household-sparse", 3),
        ("ASSIST-3D, household classes (part 1)", HERE / "per_seed", "assist3d-household", 3),
        ("B: Holodeck-style, every model per class", HERE / "per_seed", "holodeck-allmodels", 3),
        ("Holodeck-style", EMA, "holodeck-style", 3)]
# (arm, reference, reading when the arm is above by more than the reference's std [and scene0009 higher],
#  reading when below by more, whether the scene0009 condition applies)
READINGS = [("A: ASSIST-3D, household classes, sparser", "ASSIST-3D, household classes (part 1)",
             "density adds to the vocabulary", None, True),
            ("B: Holodeck-style, every model per class", "Holodeck-style",
             None, "few models per class matter", False)]


def main() -> None:
    table = print_table(ROWS)
    print()
    for arm, ref, above, below, needs_0009 in READINGS:
        if (arm, "learned") not in table or (ref, "learned") not in table:
            print(f"reading {arm[:1]}: pending (no seed yet)")
            continue
        (ra, rowa), (rb, rowb) = table[(arm, "learned")], table[(ref, "learned")]
        if len(ra) < 3 or len(rb) < 3:
            print(f"reading {arm[:1]}: pending ({len(ra)} of 3 seeds; the plan reads all three)")
            continue
        gap, sd = rowa["AP50"][0] - rowb["AP50"][0], rowb["AP50"][1]
        r9a, r9b = rowa["rooms"].get("scene0009"), rowb["rooms"].get("scene0009")
        if needs_0009 and (r9a is None or r9b is None):
            raise SystemExit("scene0009 is missing from the per-scan results: the plan's reading needs it")
        if abs(gap) <= sd:
            reading = "no effect that large (within one standard deviation of the reference)"
        elif above and gap > sd and (not needs_0009 or r9a > r9b):
            reading = above
        elif below and gap < -sd:
            reading = below
        else:
            reading = "neither: reported as it is"
        extra = f"; scene0009 {r9a:.3f} vs {r9b:.3f}" if needs_0009 else ""
        print(f"reading {arm[:1]} (plan-part2.md): learned dev AP50 {rowa['AP50'][0]:.3f} vs {rowb['AP50'][0]:.3f}, "
              f"gap {gap:+.3f} against the reference's std {sd:.3f}{extra}: {reading}")
    s0451()


def s0451() -> None:
    files = sorted(HERE.glob("hybrid-eval-s0451-part2-*.json"))
    print_s0451(s0451_per_seed(files, gens=("assist3d-household-sparse", "holodeck-allmodels")))

if __name__ == "__main__":
    main()
