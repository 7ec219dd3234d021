"""Markdown table of a scripts/fidelity.sh run: one row per training source, mean ± std over seeds,
per-room AP50, plus the geometric reference and the pooled leave-one-room-out real-only model. A
probe run with ``--hybrid`` (fidelity.sh with HYBRID=1) adds a row "SOURCE, hybrid inference" after
its own: the same models with the default inference of ``assist3d segment``.

    python scripts/fidelity_table.py OUT_DIR DEV_DIR [--json]
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

from assist3d.data import open_dataset
from assist3d.bench.evaluation.compare import room_means
from assist3d.bench.evaluation.runner import evaluate_dataset

KEYS = ("AP", "AP50", "AP25", "AR")


def per_room_ap50(per_scene: dict[str, dict]) -> dict[str, float]:
    return room_means({sid: m.get("AP50") for sid, m in per_scene.items()})


def row_from_runs(name: str, runs: list[dict]) -> dict:
    out = {"name": name, "seeds": len(runs)}
    for k in KEYS:
        vals = np.array([r[k] for r in runs], np.float64)
        out[k] = (float(vals.mean()), float(vals.std(ddof=1)) if len(vals) > 1 else 0.0)
    rooms = [per_room_ap50(r["per_scene"]) for r in runs]
    out["rooms"] = {rm: float(np.mean([x[rm] for x in rooms])) for rm in rooms[0]} if rooms else {}
    out["steps"] = int(np.mean([r["steps"] for r in runs])) if runs else 0
    out["minutes"] = float(np.mean([r["train_seconds"] for r in runs]) / 60) if runs else 0.0
    return out


def loro_rows(out: Path, dev: Path) -> dict | None:
    base = out / "probe" / "real-loro"
    folds = sorted(p for p in base.glob("*") if p.is_dir()) if base.is_dir() else []
    if not folds:
        return None
    ds = open_dataset(f"array:{dev}")
    seeds = sorted({p.name for f in folds for p in f.glob("seed_*") if (p / "result.json").is_file()})
    runs = []
    for seed in seeds:
        if not all((f / seed / "result.json").is_file() for f in folds):
            continue
        with tempfile.TemporaryDirectory() as tmp:
            for f in folds:
                for p in (f / seed / "pred").glob("*.npz"):
                    (Path(tmp) / p.name).symlink_to(p.resolve())
            res = evaluate_dataset(ds, tmp)
            d = res.to_dict(per_scene=True)
        steps = [json.loads((f / seed / "result.json").read_text()) for f in folds]
        runs.append({**{k: d[k] for k in KEYS}, "per_scene": d["per_scene"],
                     "steps": int(np.mean([s["steps"] for s in steps])),
                     "train_seconds": float(np.mean([s["train_seconds"] for s in steps]))})
    return row_from_runs("real only (leave one room out)", runs) if runs else None


def main() -> None:
    out, dev = Path(sys.argv[1]), Path(sys.argv[2])
    rows = []
    for summary in sorted((out / "probe").glob("*/summary.json")):
        data = json.loads(summary.read_text())
        rows.append(row_from_runs(summary.parent.name, data["runs"]))
        if "hybrid" in data:
            rows.append(row_from_runs(f"{summary.parent.name}, hybrid inference", data["hybrid"]["runs"]))
    loro = loro_rows(out, dev)
    if loro:
        rows.append(loro)
    geo = out / "probe" / "geometric.json"
    if geo.is_file():
        d = json.loads(geo.read_text())
        rows.append({"name": "geometric reference (no learning)", "seeds": 1, "steps": 0, "minutes": 0.0,
                     **{k: (d[k], 0.0) for k in KEYS}, "rooms": per_room_ap50(d.get("per_scene", {}))})
    if "--json" in sys.argv:
        print(json.dumps(rows, indent=1))
        return
    room_names = sorted({r for row in rows for r in row["rooms"]})
    head = ["training data", "seeds", "steps", "AP", "AP50", "AP25", "AR", *[f"AP50 {r}" for r in room_names]]
    print("| " + " | ".join(head) + " |")
    print("|" + "|".join(["---"] + ["---:"] * (len(head) - 1)) + "|")
    for row in rows:
        cells = [row["name"], str(row["seeds"]), str(row["steps"])]
        cells += [f"{row[k][0]:.3f} ± {row[k][1]:.3f}" if row["seeds"] > 1 else f"{row[k][0]:.3f}" for k in KEYS]
        cells += [f"{row['rooms'].get(r, float('nan')):.3f}" for r in room_names]
        print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
