"""plan.md's reading of run.py's figures (per_model/*.json): per room, learned against the variant; the rule.

    python experiments/structure-2026-12-07/summarize.py
"""

from __future__ import annotations

import json
import statistics
from pathlib import Path

from assist3d.bench.evaluation.compare import paired_comparison, room_means

HERE = Path(__file__).resolve().parent
VARIANT = "learned-nostructure"
HELD_OUT = {"mix-A": ("scene0006", "scene0007", "scene0008", "scene0451"),
            "mix-B": ("scene0009", "scene0010", "scene0451")}
PROBES = {"v2": HERE.parent / "scaling-2026-12-05" / "per_seed" / "probe-s250-t2000-seed_0.json",
          "mix-A": HERE.parent / "recipe2000-2026-12-07" / "per_seed" / "mix-A-seed_0.json",
          "mix-B": HERE.parent / "recipe2000-2026-12-07" / "per_seed" / "mix-B-seed_0.json"}


def rooms(res: dict, method: str, metric: str, keep: tuple[str, ...] | None) -> dict[str, float]:
    per = room_means({sid: f[metric] for sid, f in res[method]["per_scene"].items()})
    return {r: v for r, v in per.items() if keep is None or r in keep}


def main() -> None:
    verdict_parts = []
    for name in ("v2", "mix-A", "mix-B"):
        path = HERE / "per_model" / f"{name}.json"
        if not path.exists():
            print(f"{name}: not run")
            verdict_parts.append(False)
            continue
        res = json.loads(path.read_text())
        keep = HELD_OUT.get(name)
        probe = json.loads(PROBES[name].read_text())["per_scene"]
        same = all(abs(res["learned"]["per_scene"][s]["AP50"] - probe[s]["AP50"]) < 5e-4 for s in probe)
        print(f"{name} ({res['model']}): learned equals the probe's own per-scan AP50: {same}")
        for metric in ("AP50", "AP", "AP25"):
            a, b = rooms(res, "learned", metric, keep), rooms(res, VARIANT, metric, keep)
            c = paired_comparison(a, b, metric=metric)
            print(f"  {metric}: learned {statistics.mean(a.values()):.3f}, variant {statistics.mean(b.values()):.3f}, "
                  f"difference {c.mean_diff:+.3f}, 95 % interval over rooms [{c.ci95[0]:+.3f}, {c.ci95[1]:+.3f}], "
                  f"variant ahead in {c.higher}, behind in {c.lower} of {c.rooms} rooms")
            if metric == "AP50":
                print("    per room, learned / variant: " + ", ".join(f"{r} {a[r]:.3f}/{b[r]:.3f}" for r in a))
                ok = (c.higher >= 5 and c.ci95[0] > 0) if name == "v2" else c.mean_diff >= 0
                verdict_parts.append(same and ok)
        print(f"  variant's seconds on scene0451_01: {res[VARIANT]['per_scene']['scannet_scene0451_01']['seconds']}")
    print("rule: " + ("adopt the variant as segment's default" if all(verdict_parts)
                      else "not adopted: the network's own instances stay segment's default"))


if __name__ == "__main__":
    main()
