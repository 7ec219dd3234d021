"""Build the layout realism reference from labelled real scans, and score real scans honestly.

    R='array:../shared/data/real/dev?objects=annotated'
    python scripts/realism_reference.py $R --out src/assist3d/resources/realism/scannet-dev.json
    python scripts/realism_reference.py $R --loro [--json]
    python scripts/realism_reference.py $R --score assist3d:DATA/a assist3d:DATA/b [--max-scenes 50]
    python scripts/realism_reference.py $R --loro --score assist3d:DATA/a ... --matched 200

``?objects=annotated`` makes the reader count every annotated object of the real scans (lamps, boxes,
pillows as well as the 18 benchmark classes; walls and floors never), as generated scans label every
placed object: without it the real side counts fewer kinds of objects than the generated side
(128 benchmark objects against 328 annotated ones of at least 20 voxels in the 10 dev scans), and the
density statistics are then not measured the same way. The shipped reference is built with it, and
every spec given here is read with it unless it says ``?objects=benchmark`` (how the figures made
before 2026-11-29 were measured).

``--out`` writes the quantiles of every statistic of ``assist3d.bench.metrics.realism`` over the given
scans (derived statistics only: no point of a scan is stored). ``--loro`` scores each room against a
reference built from the other rooms (rescans of a room share the first 9 characters of their
name, as in ScanNet), which is how a real scan's score should be read: a scan scored against a
reference that contains it scores near 100 by construction. ``--score`` scores other datasets
against the reference built from the given scans (as ``assist3d metrics --realism-reference``), with the
score's standard error over the dataset's scenes (``realism.realism_standard_error``, seeded as
``assist3d metrics --seed 0``).
``--loro --score ... --matched B`` also scores every dataset against each held-out room's reference
(the other rooms) at the held-out room's sample size (``realism.matched_sample``, B random draws,
seeded): the KS distance grows as a sample shrinks, so a room of a dozen objects and a dataset of
thousands are only comparable at equal size. Rows ``matched`` per dataset: mean and standard
deviation over the draws, per room and averaged over rooms, beside the real rooms' own scores.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from assist3d.data import open_dataset
from assist3d.core.fileio import write_json_atomic
from assist3d.bench.metrics.realism import (RealismReference, RealismStats, matched_sample, realism_score, realism_spec,
                                            realism_standard_error, scene_stats, stats_of_dataset)
from assist3d.core.rng import make_rng


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("spec", help="labelled real scans, FORMAT:PATH")
    ap.add_argument("--out", type=Path, help="write the reference JSON here")
    ap.add_argument("--loro", action="store_true", help="score each room against the other rooms")
    ap.add_argument("--score", nargs="+", default=[], help="datasets FORMAT:PATH to score against the reference")
    ap.add_argument("--max-scenes", type=int, default=None, help="first N scenes of each --score dataset")
    ap.add_argument("--matched", type=int, default=0, metavar="B",
                    help="with --loro and --score: score each dataset at each held-out room's size, B draws")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    if args.matched and not (args.loro and args.score):
        ap.error("--matched needs --loro and --score")
    ds = open_dataset(realism_spec(args.spec))
    per_scene = {sid: scene_stats(s.coord, s.instance, f"{args.spec} scene {sid}")
                 for sid, s in ((i, ds.load(i)) for i in ds.scene_ids)}
    report: dict = {"spec": args.spec, "scenes": len(per_scene)}
    total = RealismStats()
    for st in per_scene.values():
        total.add(st)
    if args.out:
        ref = RealismReference.from_stats(total, f"{len(per_scene)} real scans ({args.spec.split('/')[-1] or args.spec})")
        write_json_atomic(args.out, ref.to_json())
        report["reference"] = {"out": str(args.out), "objects": total.objects}
    if args.loro:
        rooms = sorted({sid[:9] for sid in per_scene})
        rows, folds = {}, {}
        for r in rooms:
            held, rest = RealismStats(), RealismStats()
            for sid, st in per_scene.items():
                (held if sid[:9] == r else rest).add(st)
            ref_r = RealismReference.from_stats(rest, f"rooms other than {r}")
            score, parts, why = realism_score(held, ref_r)
            rows[r] = {"layout_realism": score, "components": parts, "reason": why, "objects": held.objects}
            folds[r] = (held, ref_r)
        report["loro"] = rows
        scores = [v["layout_realism"] for v in rows.values() if v["layout_realism"] is not None]
        report["loro_mean"] = round(sum(scores) / len(scores), 2) if scores else None
    scored = {spec: stats_of_dataset(spec, args.max_scenes) for spec in args.score}  # measured once, used twice
    if args.score:
        ref = RealismReference.from_stats(total, args.spec)
        report["scores"] = {}
        for spec, st in scored.items():
            score, parts, why = realism_score(st, ref)
            se = realism_standard_error(st, ref, make_rng(0, "layout_realism_se"))[0] if score is not None else None
            report["scores"][spec] = {"layout_realism": score, "layout_realism_se": se, "components": parts,
                                      "reason": why, "scenes": st.scenes, "objects": st.objects}
    if args.matched:
        report["matched"] = {"draws": args.matched, "datasets": {}}
        for spec, st in scored.items():
            per_room = {}
            for i, (r, (held, ref_r)) in enumerate(folds.items()):
                rng = np.random.default_rng([i, args.matched])  # the same draws for every dataset
                vals = [realism_score(matched_sample(st, held, rng), ref_r)[0] for _ in range(args.matched)]
                per_room[r] = {"mean": round(float(np.mean(vals)), 2), "std": round(float(np.std(vals)), 2)}
            means = [v["mean"] for v in per_room.values()]
            report["matched"]["datasets"][spec] = {"rooms": per_room, "mean": round(float(np.mean(means)), 2)}
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        for r, v in (report.get("loro") or {}).items():
            print(f"{r}: {v['layout_realism']}  ({v['objects']} objects) {v['components']}")
        if "loro_mean" in report:
            print(f"mean over rooms: {report['loro_mean']}")
        for spec, v in (report.get("scores") or {}).items():
            print(f"{spec}: {v['layout_realism']} +- {v['layout_realism_se']} (s.e. over scenes)  ({v['scenes']} scenes, "
                  f"{v['objects']} objects) {v['components']}")
        if "matched" in report:
            print(f"at each held-out room's size ({args.matched} draws), mean over draws per room:")
            for spec, v in report["matched"]["datasets"].items():
                cells = "  ".join(f"{r} {x['mean']}+-{x['std']}" for r, x in v["rooms"].items())
                print(f"{spec}: {v['mean']}  ({cells})")
        if "reference" in report:
            print(f"reference written to {report['reference']['out']} ({report['reference']['objects']} objects)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
