"""Whole scenes against 6 m crops (plan.md's reading): the whole-scene seeds against the scaling study's 2,000:250 point.

    python experiments/wholescene-2026-12-07/summarize.py [--copy OUT]

``--copy OUT`` first copies each finished seed's result.json from OUT/probe-s250-t2000/seed_K/ (the folder
``experiments/scaling-2026-12-05/run.sh OUT "2000:250"`` writes with ``CONFIG=.../crop0.yaml``) into per_seed/.
Figures as in the scaling study (helpers imported from the crop comparison's summarize.py): AP50 per scan, a room the
mean of its scans, a seed's figure the mean over the 6 rooms. One seed decides nothing.
"""

from __future__ import annotations

import argparse
import importlib.util
from pathlib import Path

HERE = Path(__file__).resolve().parent
_spec = importlib.util.spec_from_file_location("crop_summary", HERE.parent / "crop-2026-12-07" / "summarize.py")
crop = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(crop)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--copy", type=Path, help="the run folder to copy finished seeds from")
    a = ap.parse_args()
    if a.copy:
        crop.copy_seeds(a.copy, "probe-s250-t2000/seed_*/result.json", HERE / "per_seed", "whole-s250-t2000")
    figs = crop.print_table({
        "6 m crop (scaling 2,000:250)": crop.seeds_of(HERE.parent / "scaling-2026-12-05" / "per_seed",
                                                      "probe-s250-t2000-seed_*.json"),
        "whole scenes": crop.seeds_of(HERE / "per_seed", "whole-s250-t2000-seed_*.json")})
    whole, base = figs.get("whole scenes"), figs["6 m crop (scaling 2,000:250)"]
    if whole is None:
        return
    lower = [r for r in base[3] if whole[3][r] < base[3][r]]
    print(f"\nwhole scenes {whole[0]:.3f} against 6 m {base[0]:.3f} (difference {whole[0] - base[0]:+.3f}); "
          f"lower in {len(lower)} of 6 rooms ({', '.join(lower) or 'none'})")
    if whole[2] < 2:
        print("One seed: by plan.md this decides nothing.")
        return
    margin = max(base[1], whole[1])
    adopt = whole[0] > base[0] + margin and len(lower) <= 1
    print(f"margin {margin:.3f}: " + ("above by more than the margin and lower in at most 1 room: adopt whole scenes"
                                       if adopt else "not a clear win: 6 m stays"))


if __name__ == "__main__":
    main()
