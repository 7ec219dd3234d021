"""Table and plot of the scaling study (plan.md's reading), from the per-seed results in per_seed/.

    python experiments/scaling-2026-12-05/summarize.py [--copy OUT] [--plot docs/scaling.png]

``--copy OUT`` first copies each finished seed's result.json from the run folder OUT
(OUT/probe-sSCENES-tSTEPS/seed_K/result.json) into per_seed/. Per scan AP50 (learned: the network's
instances alone; hybrid: `segment`'s default), a room the mean of its scans (the first 9 characters of
a dev scan's name; scene0451_01 is a sixth room), a seed's figure the mean over the 6 rooms; printed
per point with the mean and spread over seeds, and the per-room means. Points with one seed are shown,
marked, and never used for a decision.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import statistics
from pathlib import Path

HERE = Path(__file__).resolve().parent
NAME = re.compile(r"probe-s(\d+)-t(\d+)-seed_(\d+)\.json$")


def room_of(scan: str) -> str:
    return "scene0451" if "scene0451" in scan else scan[:9]


def room_means(per_scene: dict) -> dict[str, float]:
    rooms: dict[str, list[float]] = {}
    for scan, fig in per_scene.items():
        rooms.setdefault(room_of(scan), []).append(fig["AP50"])
    return {r: sum(v) / len(v) for r, v in sorted(rooms.items())}


def load() -> dict[tuple[int, int], dict[int, dict]]:
    points: dict[tuple[int, int], dict[int, dict]] = {}
    for p in sorted((HERE / "per_seed").glob("*.json")):
        m = NAME.search(p.name)
        if m:
            scenes, steps, seed = map(int, m.groups())
            points.setdefault((steps, scenes), {})[seed] = json.loads(p.read_text())
    return points


def copy_from(run: Path) -> None:
    for res in sorted(run.glob("probe-s*-t*/seed_*/result.json")):
        dest = HERE / "per_seed" / f"{res.parent.parent.name}-{res.parent.name}.json"
        if not dest.exists():
            shutil.copyfile(res, dest)
            print(f"copied {dest.name}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--copy", type=Path, help="the run folder to copy finished seeds from")
    ap.add_argument("--plot", type=Path, help="write the plot (PNG) here")
    a = ap.parse_args()
    if a.copy:
        copy_from(a.copy)
    points = load()
    rows = []
    print("| steps | scenes | seeds | learned AP50 (6-room mean; per seed) | hybrid AP50 (6-room mean; per seed) |")
    print("| ---: | ---: | ---: | --- | --- |")
    for (steps, scenes), seeds in sorted(points.items()):
        figs = {}
        for kind in ("learned", "hybrid"):
            per_seed = []
            for k in sorted(seeds):
                res = seeds[k] if kind == "learned" else seeds[k]["hybrid"]
                rm = room_means(res["per_scene"])
                per_seed.append(sum(rm.values()) / len(rm))
            mean = statistics.fmean(per_seed)
            sd = statistics.stdev(per_seed) if len(per_seed) > 1 else float("nan")
            figs[kind] = (mean, sd, per_seed)
        rows.append((steps, scenes, len(seeds), figs))
        cell = {k: f"{m:.3f} ± {s:.3f} ({', '.join(f'{x:.3f}' for x in v)})" if len(v) > 1
                else f"{m:.3f} (one seed)" for k, (m, s, v) in figs.items()}
        print(f"| {steps} | {scenes} | {len(seeds)} | {cell['learned']} | {cell['hybrid']} |")
    shipped = HERE / "shipped" / "hybrid_eval-shipped.json"
    ship_cells: dict = {}
    if shipped.exists():  # the shipped model, measured the same way (scripts/hybrid_eval.py)
        model = next(iter(json.loads(shipped.read_text())["models"].values()))
        ship_cells = {}
        for kind in ("learned", "hybrid"):
            scans = {s: {"AP50": v["AP50"]} for g in model[kind] for s, v in g["scans"].items()}
            rm = room_means(scans)
            ship_cells[kind] = (sum(rm.values()) / len(rm), rm)
        print(f"| model v1, shipped before (821 steps, 60 scenes) | | 1 | {ship_cells['learned'][0]:.3f} | {ship_cells['hybrid'][0]:.3f} |")
        print()
        print("Model v1 (shipped before) per room, learned / hybrid: " + ", ".join(
            f"{r} {ship_cells['learned'][1][r]:.3f}/{ship_cells['hybrid'][1][r]:.3f}" for r in ship_cells["learned"][1]))
    print()
    print("Per room, learned / hybrid AP50, mean over seeds:")
    for (steps, scenes), seeds in sorted(points.items()):
        per_room: dict[str, list[tuple[float, float]]] = {}
        for res in seeds.values():
            lr, hr = room_means(res["per_scene"]), room_means(res["hybrid"]["per_scene"])
            for r in lr:
                per_room.setdefault(r, []).append((lr[r], hr[r]))
        cells = ", ".join(f"{r} {statistics.fmean(x for x, _ in v):.3f}/{statistics.fmean(y for _, y in v):.3f}"
                          for r, v in per_room.items())
        print(f"- {steps} steps, {scenes} scenes ({len(seeds)} seeds): {cells}")
    if a.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        # left: against steps at 250 scenes (the steps curve); right: against scenes at 2,000 steps
        fig, (ax, bx) = plt.subplots(1, 2, figsize=(10.0, 4.0), dpi=120, sharey=True)
        kinds = (("learned", "tab:blue"), ("hybrid", "tab:orange"))

        def curve(panel, pts, vary: int, kind: str, colour: str, fmt: str, label: str, **style) -> None:
            """The mean over seeds as a line, each seed as a dot."""
            panel.plot([r[vary] for r in pts], [r[3][kind][0] for r in pts], fmt, color=colour, label=label, **style)
            for r in pts:
                panel.scatter([r[vary]] * len(r[3][kind][2]), r[3][kind][2], color=colour, s=10, alpha=0.5)

        def mark_one_seed(panel, pts, vary: int) -> None:
            for r in pts:
                if r[2] < 2:
                    panel.annotate("one seed", (r[vary], r[3]["learned"][0]), textcoords="offset points",
                                   xytext=(4, -12), fontsize=7)

        for panel, fixed, vary, label in ((ax, (1, 250), 0, "training steps (batch 2), 250 scenes"),
                                          (bx, (0, 2000), 1, "generated training scenes, 2,000 steps")):
            pts_all = sorted((r for r in rows if r[fixed[0]] == fixed[1]), key=lambda r: r[vary])
            for kind, colour in kinds:
                curve(panel, pts_all, vary, kind, colour, "-o", f"{kind}, mean of seeds")
                if shipped.exists():
                    panel.axhline(ship_cells[kind][0], color=colour, ls=":", lw=1,
                                  label=f"model v1 (shipped before), {kind}")
            mark_one_seed(panel, pts_all, vary)
            panel.set_xscale("log")
            panel.set_xticks([r[vary] for r in pts_all], [str(r[vary]) for r in pts_all])
            panel.minorticks_off()
            panel.set_xlabel(label)
            panel.grid(alpha=0.3)
        # other scene counts measured at two or more step counts: their learned steps curve, lighter, on the left
        for scenes in sorted({r[1] for r in rows} - {250}):
            pts = sorted((r for r in rows if r[1] == scenes), key=lambda r: r[0])
            if len(pts) < 2:
                continue
            curve(ax, pts, 0, "learned", "tab:green", "--s", f"learned, {scenes:,} scenes", ms=4)
            mark_one_seed(ax, pts, 0)
            ax.set_xlabel("training steps (batch 2); 250 scenes unless the legend names another count")
        ax.set_ylabel("AP50, mean over 6 real rooms")
        ax.set_title("against training steps", fontsize=10)
        bx.set_title("against training scenes", fontsize=10)
        fig.suptitle("Real-scan AP50 of the segmenter trained on ASSIST-3D data (dots: seeds)", fontsize=10)
        ax.legend(fontsize=7)
        if any(r[1] == 2000 for r in rows):  # the point's two deviations (plan.md)
            bx.text(0.98, 0.03, "2,000 scenes: ray-budget render; at 2,000 steps float32 (plan.md)", transform=bx.transAxes,
                    ha="right", va="bottom", fontsize=7)
        fig.tight_layout()
        a.plot.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(a.plot, metadata={"Software": None})
        print(f"wrote {a.plot}")


if __name__ == "__main__":
    main()
