"""Exploratory, from figures already measured: how much hybrid inference adds as a function of how good the
network's own instances are (dev AP50, clean scans, hybrid without the plane refit, every 200-step model
whose learned and hybrid figures were both recorded).

    python experiments/learned-vs-hybrid-2026-11-28/gain.py

Models: the per-seed files of ../fidelity-ema-2026-11-27/ and ../holodeck-why-2026-11-28/ that hold a hybrid
figure, and the nine household-sparse models scored clean in ../noise-2026-11-28/spread2/ (distinct models:
arm A's seeds 0-1 there are the retrained ones). Beside them, not pooled: the ship candidate's three 821-step
seeds (clean, with the plane refit).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
RESULTS = HERE.parent
sys.path.insert(0, str(RESULTS / "ship-candidate-2026-11-28"))
sys.path.insert(0, str(RESULTS / "noise-2026-11-28"))
from rule import figures  # noqa: E402
from spread2_table import FILES, ap50  # noqa: E402  (the spread2 files, checked as that table reads them)


def models() -> list[tuple[str, float, float]]:
    """(name, learned AP50, hybrid AP50) of every 200-step model with both figures, no plane refit."""
    out = []
    for folder in ("fidelity-ema-2026-11-27", "holodeck-why-2026-11-28"):
        for p in sorted((RESULTS / folder / "per_seed").glob("*.json")):
            d = json.loads(p.read_text())
            if isinstance(d.get("hybrid"), dict) and d.get("steps") == 200:
                out.append((f"{folder[:-11]}/{p.stem}", d["AP50"], d["hybrid"]["AP50"]))
    for p in sorted(FILES.glob("*-clean.json")):
        out.append((f"household-sparse/{p.stem.removesuffix('-clean')}",
                    ap50(p.name, "learned", 0.0, None), ap50(p.name, "hybrid", 0.0, None)))
    return out


def main() -> None:
    rows = models()
    learned = np.array([r[1] for r in rows])
    gain = np.array([r[2] - r[1] for r in rows])
    slope, icept = np.polyfit(learned, gain, 1)
    r = float(np.corrcoef(learned, gain)[0, 1])
    print(f"{len(rows)} models (200 steps, clean dev scans, hybrid without the plane refit)")
    for lo, hi in ((0.0, 0.05), (0.05, 0.10), (0.10, 0.15), (0.15, 1.0)):
        sel = (learned >= lo) & (learned < hi)
        if sel.any():
            print(f"  learned AP50 in [{lo:.2f}, {hi:.2f}): {sel.sum():2d} models, hybrid gain "
                  f"{gain[sel].mean():+.3f} (min {gain[sel].min():+.3f}, max {gain[sel].max():+.3f}), "
                  f"hybrid below learned in {int((gain[sel] < 0).sum())}")
    print(f"  gain = {icept:+.3f} {slope:+.3f} x learned (least squares), correlation {r:+.2f}; "
          f"the line crosses zero at learned AP50 {-icept / slope:.3f}")
    # The gain holds the learned figure with a minus sign, so its correlation with it is partly built in;
    # the hybrid figure itself against the learned one has no such coupling.
    hybrid = learned + gain
    hs, hi = np.polyfit(learned, hybrid, 1)
    print(f"  hybrid = {hi:.3f} {hs:+.3f} x learned (least squares), correlation {np.corrcoef(learned, hybrid)[0, 1]:+.2f}; "
          f"hybrid AP50 over the models {hybrid.mean():.3f} ± {hybrid.std(ddof=1):.3f}, learned {learned.mean():.3f} ± "
          f"{learned.std(ddof=1):.3f}")
    print("beside it, the ship candidate's 821-step seeds (clean dev scans, with the plane refit):")
    for name, folder in (("seed 0", RESULTS / "ship-candidate-2026-11-28"),
                         ("seed 1", RESULTS / "ship-candidate-2026-11-28" / "seed1"),
                         ("seed 2", RESULTS / "ship-candidate-2026-11-28" / "seed2")):
        if (folder / "r2-clean.json").exists():
            lc, hc = figures(folder, "learned")["dev"][0], figures(folder, "hybrid")["dev"][0]
            print(f"  {name}: learned {lc:.3f}, hybrid {hc:.3f}, gain {hc - lc:+.3f}")


if __name__ == "__main__":
    main()
