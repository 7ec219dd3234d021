"""Table and reading of the household-vocabulary run (plan.md beside this file).

    python experiments/holodeck-why-2026-11-28/table.py

Rows: ASSIST-3D with the household classes (per_seed/assist3d-household-seedK.json here, each a probe
seed's result.json), ASSIST-3D seeds 0-5 and Holodeck-style seeds 0-2 of the generator comparison with
today's defaults (../fidelity-ema-2026-11-27/per_seed/). Then the plan's reading, fixed before the runs,
and the household models on scene0451_01 (hybrid-eval-s0451-*.json here, metrics only).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from assist3d.bench.evaluation.compare import room_of

HERE = Path(__file__).resolve().parent
EMA = HERE.parent / "fidelity-ema-2026-11-27" / "per_seed"
sys.path.insert(0, str(HERE.parents[1] / "scripts"))
from fidelity_table import row_from_runs  # noqa: E402  (the per-room and mean/std rows of fidelity.sh's table)

ROWS = [("ASSIST-3D, household classes", HERE / "per_seed", "assist3d-household", 3),
        ("ASSIST-3D", EMA, "assist3d", 6),
        ("Holodeck-style", EMA, "holodeck-style", 3)]


def runs(folder: Path, gen: str, max_seeds: int, part: str, hybrid_dirs: tuple[Path, ...] = (HERE,)) -> list[dict]:
    numbered = sorted((int(f.stem.rsplit("seed", 1)[1]), f) for f in folder.glob(f"{gen}-seed*.json"))
    out = []
    for k, f in numbered:
        if k >= max_seeds:
            continue
        r = json.loads(f.read_text())
        out.append(r if part == "learned" else hybrid_without_refit(r, gen, k, hybrid_dirs))
    return out


def hybrid_without_refit(run: dict, gen: str, seed: int, hybrid_dirs: tuple[Path, ...] = (HERE,)) -> dict:
    """A seed's hybrid figures as every hybrid figure of these tables was made: without the plane refit
    adopted on 2026-11-28. The probe's own when it made them so (its ``inference`` records no refit or
    refit 0); else the model's row in a ``hybrid-eval-dev-*-r0.json`` file of ``hybrid_dirs`` (scripts/hybrid_eval.py
    --refine-planes 0 on the dev scans), with the seed's steps and training time."""
    h = run.get("hybrid")
    if isinstance(h, dict) and h.get("inference", {}).get("geometric", {}).get("refine", 0) == 0:
        return h
    for f in [f for d in hybrid_dirs for f in sorted(d.glob("hybrid-eval-dev-*-r0.json"))]:
        d = json.loads(f.read_text())
        if d.get("hybrid_geometric", {}).get("refine") != 0 or len(d["eval"]) != 1:
            raise SystemExit(f"{f}: expected hybrid_eval.py --refine-planes 0 with one --eval spec (the dev scans)")
        for path, rows in d["models"].items():
            if Path(path).parts[-3:-1] == (gen, f"seed_{seed}"):
                row = rows["hybrid"][0]
                return {**{k: row[k] for k in ("AP", "AP50", "AP25", "AR")}, "per_scene": row["scans"],
                        "steps": run["steps"], "train_seconds": run["train_seconds"]}
    raise SystemExit(f"{gen} seed {seed}: no hybrid figures without the plane refit; run scripts/hybrid_eval.py "
                     f"MODEL --eval array:../shared/data/real/dev --refine-planes 0 --out "
                     f"{hybrid_dirs[-1]}/hybrid-eval-dev-NAME-r0.json")


def s0451_per_seed(files: list[Path], gens: tuple[str, ...] | None = None) -> dict[tuple[str, str], dict[int, float]]:
    """AP50 on scene0451_01 per (generator, "learned" | "hybrid") and seed, from scripts/hybrid_eval.py files
    made with ``--refine-planes 0`` and the one --eval spec scene0451_01; ``gens`` limits the models allowed."""
    per: dict[tuple[str, str], dict[int, float]] = {}
    for f in files:
        d = json.loads(f.read_text())
        if len(d["eval"]) != 1 or "scene0451_01" not in d["eval"][0]:
            raise SystemExit(f"{f}: expected one --eval spec, scannet_scene0451_01, not {d['eval']}")
        if d.get("hybrid_geometric", {}).get("refine") != 0:  # files that do not record it may hold refits
            raise SystemExit(f"{f}: not recorded as made without the plane refit, as part 1's figures were "
                             f"(scripts/hybrid_eval.py --refine-planes 0)")
        for path, rows in d["models"].items():
            parts = Path(path).parts  # .../probe/GEN/seed_K/model.pt
            gen, seed = parts[-3], int(parts[-2].removeprefix("seed_"))
            if gens is not None and gen not in gens:
                raise SystemExit(f"{f}: {path} is not a model of {', '.join(gens)}")
            for part in ("learned", "hybrid"):
                if seed in per.get((gen, part), {}):
                    raise SystemExit(f"{f}: {gen} seed {seed} is also in another file")
                per.setdefault((gen, part), {})[seed] = rows[part][0]["AP50"]
    return per


def print_s0451(per: dict[tuple[str, str], dict[int, float]], show_seeds: bool = False) -> None:
    """One line per (generator, part): mean ± std over its seeds and each seed's AP50."""
    for (gen, part), seeds in sorted(per.items()):
        v = np.array([seeds[k] for k in sorted(seeds)])
        sd = v.std(ddof=1) if len(v) > 1 else float("nan")
        label = f"seeds {sorted(seeds)}: " if show_seeds else ""
        print(f"scene0451_01 {gen} {part}: {v.mean():.3f} ± {sd:.3f} ({label}" + " / ".join(f"{x:.3f}" for x in v) + ")")


def print_table(rows: list[tuple[str, Path, str, int]], hybrid_dirs: tuple[Path, ...] = (HERE,)) -> dict:
    """Print the markdown table of ``rows`` ((name, folder, generator, seeds)); returns
    ``{(name, "learned" | "hybrid"): (runs, row)}`` for the readings."""
    table: dict = {}
    for name, folder, gen, k in rows:
        for part in ("learned", "hybrid"):
            rs = runs(folder, gen, k, part, hybrid_dirs)
            if rs:
                table[(name, part)] = (rs, row_from_runs(name, rs))
    rooms = sorted({room_of(s) for rs, _ in table.values() for r in rs for s in r["per_scene"]})
    print("AP50 per seed is pooled over the 10 scans; the room columns are means of per-scan AP50 (over the "
          "room's scans and the seeds), so they do not average to it.\n")
    print("| training data | inference | seeds | AP50 mean ± std | AP50 per seed | AP25 mean | "
          + " | ".join(f"AP50 {r}" for r in rooms) + " |")
    print("|---|---|---:|---:|---|---:|" + "---:|" * len(rooms))
    for part in ("learned", "hybrid"):
        for name, *_ in rows:
            if (name, part) not in table:
                continue
            rs, row = table[(name, part)]
            sd = row["AP50"][1] if len(rs) > 1 else float("nan")
            print(f"| {name} | {part} | {len(rs)} | {row['AP50'][0]:.3f} ± {sd:.3f} | "
                  + " / ".join(f"{r['AP50']:.3f}" for r in rs) + f" | {row['AP25'][0]:.3f} | "
                  + " | ".join(f"{row['rooms'][k]:.3f}" for k in rooms) + " |")
    return table


def main() -> None:
    table = print_table(ROWS)
    arm, base = ("ASSIST-3D, household classes", "learned"), ("ASSIST-3D", "learned")
    if arm in table and base in table:
        (ra, rowa), (rb, rowb) = table[arm], table[base]
        gap = rowa["AP50"][0] - rowb["AP50"][0]
        sd = rowb["AP50"][1]
        r9a, r9b = rowa["rooms"].get("scene0009"), rowb["rooms"].get("scene0009")
        if len(ra) < 3 or len(rb) < 6:
            reading = "pending (the plan reads 3 seeds of the arm against 6 of ASSIST-3D)"
        elif r9a is None or r9b is None:
            raise SystemExit("scene0009 is missing from the per-scan results: the plan's reading needs it")
        elif gap > sd and r9a is not None and r9a > r9b:
            reading = "the vocabulary carries Holodeck-style's learned lead"
        elif abs(gap) <= sd:
            reading = "it does not (within one ASSIST-3D standard deviation)"
        else:
            reading = "neither: reported as it is"
        print(f"\nreading (plan.md): learned dev AP50 gap {gap:+.3f} against ASSIST-3D's std {sd:.3f} over "
              f"{len(rb)} seeds; scene0009 {r9a if r9a is not None else float('nan'):.3f} vs "
              f"{r9b if r9b is not None else float('nan'):.3f}; seeds {len(ra)}: {reading}")
    s0451()


def s0451() -> None:
    files = sorted(HERE.glob("hybrid-eval-s0451-household*.json"))
    per: dict[str, dict[int, float]] = {}
    geo = None
    for f in files:
        d = json.loads(f.read_text())
        if len(d["eval"]) != 1 or "scene0451_01" not in d["eval"][0]:
            raise SystemExit(f"{f}: expected one --eval spec, scannet_scene0451_01, not {d['eval']}")
        g = d["control"]["geometric"][0]["AP50"]
        if geo is not None and g != geo:
            raise SystemExit(f"{f}: its geometric reference differs from the other files'")
        geo = g
        for path, rows in d["models"].items():
            parts = Path(path).parts  # .../probe/assist3d-household/seed_K/model.pt
            if parts[-3] != "assist3d-household":
                raise SystemExit(f"{f}: {path} is not a model of the household run")
            seed = int(parts[-2].removeprefix("seed_"))
            if seed >= 3:
                continue
            for part in ("learned", "hybrid"):
                if seed in per.get(part, {}):
                    raise SystemExit(f"{f}: seed {seed} is also in another file")
                per.setdefault(part, {})[seed] = rows[part][0]["AP50"]
    if not per:
        return
    print(f"\nscene0451_01, AP50 of the household models (geometric reference {geo:.3f}):")
    for part, seeds in per.items():
        v = np.array([seeds[k] for k in sorted(seeds)])
        sd = v.std(ddof=1) if len(v) > 1 else float("nan")
        print(f"  {part}: {v.mean():.3f} ± {sd:.3f} (" + " / ".join(f"{x:.3f}" for x in v) + ")")


if __name__ == "__main__":
    main()
