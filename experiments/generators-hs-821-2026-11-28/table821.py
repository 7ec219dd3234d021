"""Table and readings of plan.md beside this file (the household-sparse comparison at 821 steps).

    python experiments/generators-hs-821-2026-11-28/table821.py

ASSIST-3D: the ship candidate's three seeds (../ship-candidate-2026-11-28/result.json, seed1/, seed2/).
Baselines: per_seed/GEN-household-sparse-seedK.json here (each a probe seed's result.json). The plan's
amendment: eval/GEN-K/ here (six evaluations each, experiments/tools/noise_robustness.py), ASSIST-3D's the candidate's.
A baseline with fewer than three seeds is reported as partial, without a verdict.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
CAND = HERE.parent / "ship-candidate-2026-11-28"
sys.path.insert(0, str(CAND))
sys.path.insert(0, str(HERE.parent / "noise-2026-11-28"))
from rule import figures  # noqa: E402  (six evaluation files of one model, checked as the candidate's rule reads them)
from spread2_table import spreads  # noqa: E402  (pooled seed and draw spreads)

ASSIST = "assist3d"
GENS = {ASSIST: "ASSIST-3D", "mesh-sampled": "mesh-sampled", "randomrooms": "RandomRooms-style"}
CAND_DIRS = [CAND, CAND / "seed1", CAND / "seed2"]


def results(gen: str) -> list[dict]:
    if gen == ASSIST:
        return [json.loads((d / "result.json").read_text()) for d in CAND_DIRS]
    out = [json.loads(p.read_text()) for p in sorted((HERE / "per_seed").glob(f"{gen}-household-sparse-seed*.json"))]
    if any(r["steps"] != 821 for r in out):
        raise SystemExit(f"{gen}: a per-seed file not trained for 821 steps")
    return sorted(out, key=lambda r: r["seed"])


def eval_dirs(gen: str) -> list[Path]:
    if gen == ASSIST:
        return CAND_DIRS
    return [d for d in (HERE / "eval" / f"{gen}-{k}" for k in range(3)) if len(list(d.glob("r2-*.json"))) == 6]


def main() -> None:
    rows = {g: results(g) for g in GENS}
    print("learned dev AP50 (the probe's figure), 821 steps, household-sparse data")
    for g, rs in rows.items():
        v = np.array([r["AP50"] for r in rs])
        sd = f" ± {v.std(ddof=1):.3f}" if len(v) > 1 else ""
        print(f"  {GENS[g]:18s} {len(v)} seed(s): " + (f"{v.mean():.3f}{sd} (" + ", ".join(f"{x:.3f}" for x in v) + ")"
                                                      if len(v) else "none yet"))
    a = np.array([r["AP50"] for r in rows[ASSIST]])
    for g in ("mesh-sampled", "randomrooms"):
        b = np.array([r["AP50"] for r in rows[g]])
        if len(b) < 3:
            print(f"reading against {GENS[g]}: partial ({len(b)} of 3 seeds), no verdict")
            continue
        gap, sd = a.mean() - b.mean(), max(a.std(ddof=1), b.std(ddof=1))
        verdict = "ASSIST-3D leads it at 821 steps" if gap > sd else "not met against it at 821 steps"
        print(f"reading against {GENS[g]}: gap {gap:+.3f} against the larger std {sd:.3f}, ahead in "
              f"{int(np.sum(a > b))} of 3 paired seeds: {verdict}")
    print("the amendment: six evaluations per model (clean + five 1 mm draws, today's inference), dev AP50")
    evals = {g: eval_dirs(g) for g in GENS}
    figs = {g: [{m: figures(d, m) for m in ("learned", "hybrid")} for d in dirs] for g, dirs in evals.items()}
    for g, dirs in evals.items():
        for i, (d, f) in enumerate(zip(dirs, figs[g])):
            print(f"  {GENS[g]:18s} {d.name if g != ASSIST else f'seed {i}'}: "
                  + "   ".join(f"{m} clean {f[m]['dev'][0]:.3f}, draws {np.mean(f[m]['dev'][1:]):.3f}; "
                             f"scene0451_01 clean {f[m]['scannet_scene0451_01.npy'][0]:.3f}" for m in f))
    if any(len(d) < 3 for d in evals.values()):
        print("  reading of the amendment: partial (" + ", ".join(f"{GENS[g]} {len(d)}" for g, d in evals.items())
              + " of 3 models), no verdict")
        return
    dev = np.array([[f["hybrid"]["dev"] for f in figs[g]] for g in GENS])  # (gens, seeds, 6)
    clean, draws = dev[..., 0], dev[..., 1:]
    sd_a, sd_b, within = spreads(clean, draws)
    gaps_a = [(clean[0].mean() - clean[j].mean()) / sd_a for j in (1, 2)]
    gaps_b = [(draws[0].mean() - draws[j].mean()) / sd_b for j in (1, 2)]
    ok = sd_b < sd_a / 2 and all(gb > ga for ga, gb in zip(gaps_a, gaps_b))
    print(f"  hybrid dev, pooled seed sd: (a) clean {sd_a:.3f}, (b) draw means {sd_b:.3f}; within-model over "
          f"draws {within:.3f}; ASSIST-3D's gaps in seed sd, (a) " + ", ".join(f"{x:+.1f}" for x in gaps_a)
          + ", (b) " + ", ".join(f"{x:+.1f}" for x in gaps_b))
    print("  reading: " + ("a hybrid evaluation over noise draws separates generators better (next: a probe opt-in)"
                           if ok else "reported as it is (the amendment's condition does not hold)"))


if __name__ == "__main__":
    main()
