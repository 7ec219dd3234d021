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

        fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=120)
        for kind, colour in (("learned", "tab:blue"), ("hybrid", "tab:orange")):
            for scenes in sorted({s for _, s, _, _ in rows}):
                pts = [(st, f[kind]) for st, sc, _, f in rows if sc == scenes]
                xs = [st for st, _ in pts]
                ax.plot(xs, [f[0] for _, f in pts], "-o", color=colour, alpha=1.0 if scenes == 250 else 0.5,
                        label=f"{kind}, {scenes} scenes")
                for st, (m, s, v) in pts:
                    ax.scatter([st] * len(v), v, color=colour, s=10, alpha=0.5)
        if shipped.exists():
            for kind, colour in (("learned", "tab:blue"), ("hybrid", "tab:orange")):
                ax.axhline(ship_cells[kind][0], color=colour, ls=":", lw=1, label=f"model v1 (shipped before), {kind}")
        one = [st for st, _, n, _ in rows if n < 2]
        if one:
            ax.annotate("one seed so far", (one[-1], rows[-1][3]["learned"][0]), textcoords="offset points",
                        xytext=(-70, 12), fontsize=7)
        ax.set_xscale("log")
        ax.set_xticks([st for st, _, _, _ in rows], [str(st) for st, _, _, _ in rows])
        ax.minorticks_off()
        ax.set_xlabel("training steps (batch 2)")
        ax.set_ylabel("AP50, mean over 6 real rooms")
        ax.set_title("Real-scan AP50 against training steps (ASSIST-3D data)", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        a.plot.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(a.plot, metadata={"Software": None})
        print(f"wrote {a.plot}")


if __name__ == "__main__":
    main()
