"""Reading of plan-refine.md: least-squares refits of the RANSAC planes (GeometricConfig.refine = 2)
against today's planes (refine = 0), on the clean scans and 1 mm noise draws 0-4, shipped model.

    python experiments/noise-2026-11-28/refine_table.py

refine 0: noise-base.json (sigma 0) and noise-1mm-seed*.json; refine 2: refine/r2-clean.json and
refine/r2-1mm-seed*.json; steadiness: change-1mm-{geometric,hybrid}.json against
refine/change-r2-{geometric,hybrid}.json (all beside this file, made by experiments/tools/noise_robustness.py).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def ap50(path: Path, sigma: float, method: str) -> tuple[float, float]:
    d = json.loads(path.read_text())
    row = next(r for r in d["rows"] if r["sigma"] == sigma and r["method"] == method and not r["denoise"])
    dev, s0451 = d["eval"]
    if not (dev.endswith("/dev") and s0451.endswith("scannet_scene0451_01.npy")):
        raise SystemExit(f"{path}: expected the dev scans and scene0451_01, got {d['eval']}")
    return row[dev]["AP50"], row[s0451]["AP50"]


def main() -> None:
    evals = [("clean", HERE / "noise-base.json", HERE / "refine" / "r2-clean.json", 0.0)]
    evals += [(f"1 mm draw {s}", HERE / f"noise-1mm-seed{s}.json", HERE / "refine" / f"r2-1mm-seed{s}.json", 0.001)
              for s in range(5)]
    print("| evaluation | method | dev refine 0 | dev refine 2 | scene0451_01 refine 0 | scene0451_01 refine 2 |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    diffs: dict[str, list[tuple[float, float]]] = {}
    for name, f0, f2, sigma in evals:
        for method in ("geometric", "hybrid"):
            a, b = ap50(f0, sigma, method), ap50(f2, sigma, method)
            print(f"| {name} | {method} | {a[0]:.3f} | {b[0]:.3f} | {a[1]:.3f} | {b[1]:.3f} |")
            diffs.setdefault(method, []).append((b[0] - a[0], b[1] - a[1]))
    print()
    for method, d in diffs.items():
        arr = np.array(d)
        print(f"{method}: paired mean AP50 difference (refine 2 - refine 0) over {len(arr)} evaluations: "
              f"dev {arr[:, 0].mean():+.4f}, scene0451_01 {arr[:, 1].mean():+.4f}")
    steadier = {}
    for method in ("geometric", "hybrid"):
        c0 = json.loads((HERE / f"change-1mm-{method}.json").read_text())
        c2 = json.loads((HERE / "refine" / f"change-r2-{method}.json").read_text())
        m0 = c0["top20_clean_mask_best_iou_with_noisy"]["median"]
        m2 = c2["top20_clean_mask_best_iou_with_noisy"]["median"]
        steadier[method] = m2 > m0
        print(f"{method}: median best IoU of the top-20 clean masks with a noisy mask {m0:.3f} -> {m2:.3f}; "
              f"objects crossing IoU 0.5 {c0['crossings_of_iou_0.5']} -> {c2['crossings_of_iou_0.5']} "
              f"(of {c2['objects']})")
    hyb = np.array(diffs["hybrid"])
    not_lower = hyb[:, 0].mean() >= -0.005 and hyb[:, 1].mean() >= -0.005
    print(f"\nreading (plan-refine.md): steadier {all(steadier.values())} (geometric {steadier['geometric']}, "
          f"hybrid {steadier['hybrid']}); hybrid not lower {not_lower} -> "
          + ("hybrid inference uses refine 2" if all(steadier.values()) and not_lower else "refine stays 0"))


if __name__ == "__main__":
    main()
