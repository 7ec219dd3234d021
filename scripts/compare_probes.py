"""Paired, per-scan comparison of two recipes on the same real scans (``bench/evaluation/compare.py``).

    python scripts/compare_probes.py A B [--metric AP50] [--json OUT.json]

A and B are each either a probe folder (``assist3d probe --out DIR``: the network's instances alone,
per-scan figures of every finished seed, averaged over seeds; ``DIR:hybrid`` for the figures of
hybrid inference of a probe run with ``--hybrid``, ``DIR:learned`` the same as ``DIR``; a folder
whose own name ends in ``:hybrid`` is read as a folder) or ``FILE.json:ROW``, the output of
``scripts/hybrid_eval.py`` with one of its rows (``hybrid``, ``learned``, ...), averaged over every
model in the file. Prints the mean per-scan figures of both sides, the mean difference B - A with a
95 % interval that resamples rooms (the models at hand), a second interval that also resamples each
side's runs (the recipes: seeds differ by as much as recipes do; drawn together when A and B are two
rows of the same models: two rows of one FILE.json, or DIR and DIR:hybrid), each run's mean over the scans,
the scans each side wins and the difference per room.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from assist3d.bench.evaluation.compare import mean_over_runs, recipe_comparison
from assist3d.core.fileio import write_json_atomic


def per_run(source: str, metric: str) -> list[dict[str, float]]:
    """Per-scan ``metric`` of each seed of a probe folder or each model of ``FILE.json:ROW``."""
    path = Path(source)
    file, _, row = source.rpartition(":")
    if not path.is_dir() and file and Path(file).is_dir() and row not in ("learned", "hybrid"):
        raise SystemExit(f"{source}: a probe folder has the rows 'learned' and 'hybrid', not {row!r}")
    if path.is_dir() or (file and Path(file).is_dir()):
        folder = path if path.is_dir() else Path(file)
        results = sorted(folder.glob("seed_*/result.json"))
        if not results:
            raise SystemExit(f"{folder}: no seed_*/result.json (an unfinished probe?)")
        runs = []
        for p in results:
            res = json.loads(p.read_text())
            if not path.is_dir() and row == "hybrid":
                if "hybrid" not in res:
                    raise SystemExit(f"{p}: no hybrid figures (run the probe again with --hybrid)")
                res = res["hybrid"]
            runs.append({s: v[metric] for s, v in res["per_scene"].items()})
        return runs
    if not file or not Path(file).is_file():
        raise SystemExit(f"{source}: neither a probe folder nor FILE.json:ROW")
    models = json.loads(Path(file).read_text())["models"]
    runs = []
    for name, rows in models.items():
        if row not in rows:
            raise SystemExit(f"{file}: model {name} has no row {row!r} (rows: {', '.join(rows)})")
        scans: dict[str, float] = {}
        for group in rows[row]:
            if "scans" not in group:
                raise SystemExit(f"{file}: no per-scan figures (written by an older scripts/hybrid_eval.py)")
            scans |= {s: v[metric] for s, v in group["scans"].items()}
        runs.append(scans)
    return runs


def same_models(a: str, b: str) -> bool:
    """True when A and B are two rows of the same models: two rows of one FILE.json, or a probe
    folder's learned and hybrid figures; their runs are then paired model by model."""
    def base(source: str) -> str:
        path = Path(source)
        if path.is_dir():
            return str(path.resolve())
        file, _, _row = source.rpartition(":")
        return str(Path(file).resolve()) if file else source

    return base(a) == base(b)


def per_scan(source: str, metric: str) -> tuple[dict[str, float], int]:
    """Per-scan ``metric`` of a probe folder or ``FILE.json:ROW``, averaged over seeds or models."""
    runs = per_run(source, metric)
    return mean_over_runs(runs), len(runs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--metric", default="AP50", choices=("AP", "AP50", "AP25"))
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    ra, rb = per_run(args.a, args.metric), per_run(args.b, args.metric)
    paired = same_models(args.a, args.b)
    try:
        r = recipe_comparison(ra, rb, metric=args.metric, paired_runs=paired)
    except ValueError as e:
        raise SystemExit(f"{args.a} vs {args.b}: {e}") from None
    c = r.paired
    print(f"{args.metric} per scan, mean over {c.scans} scans ({c.rooms} rooms): A {c.mean_a:.3f} ({len(ra)} runs), "
          f"B {c.mean_b:.3f} ({len(rb)} runs)")
    print(f"B - A: {c.mean_diff:+.3f}, 95 % interval over rooms [{c.ci95[0]:+.3f}, {c.ci95[1]:+.3f}], over rooms "
          f"and {'paired ' if paired else ''}runs [{r.ci95[0]:+.3f}, {r.ci95[1]:+.3f}]; B higher on {c.higher}, "
          f"lower on {c.lower}, equal on {c.equal} scans")
    print("each run's mean over the scans: A " + ", ".join(f"{x:.3f}" for x in r.runs_a)
          + "; B " + ", ".join(f"{x:.3f}" for x in r.runs_b))
    print("per room: " + ", ".join(f"{room} {d:+.3f}" for room, d in c.per_room.items()))
    if args.json:
        write_json_atomic(args.json, {"a": args.a, "b": args.b, "runs_a": len(ra), "runs_b": len(rb),
                                      "paired_runs": paired} | r.to_json())


if __name__ == "__main__":
    main()
