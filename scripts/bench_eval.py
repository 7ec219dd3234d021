"""Time the class-agnostic evaluation on a ScanNet-validation-sized synthetic set.

312 scenes (ScanNet v2 val), each with 80k-150k points, 20-60 GT objects and ~100 predictions
(a noisy copy of most objects, duplicates, fragments, blobs on void). Reports the time of matching
plus the pooled AP/AR (the part ``assist3d evaluate`` adds on top of reading files), and, with
``--io``, the time to write and read the predictions as compressed ``.npz`` for a subset.

    .venv/bin/python scripts/bench_eval.py [--scenes 312] [--io 20]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from assist3d.bench.evaluation import load_predictions, match_scene, save_predictions, summarize


def synthetic_scene(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(instance (N,) int32, masks (M, N) bool, scores (M,) float32)."""
    n = int(rng.integers(80_000, 150_000))
    g = int(rng.integers(20, 61))
    # object sizes: log-normal, the rest of the points void
    sizes = np.maximum(30, rng.lognormal(7.0, 1.0, g)).astype(np.int64)
    sizes = np.minimum(sizes, n // (2 * g))
    labels = np.full(n, -1, np.int32)
    labels[: sizes.sum()] = np.repeat(np.arange(g, dtype=np.int32), sizes)
    labels = labels[rng.permutation(n)]
    point_of = [np.flatnonzero(labels == k) for k in range(g)]
    void = np.flatnonzero(labels < 0)
    masks: list[np.ndarray] = []
    for k in range(g):
        if rng.random() < 0.15:  # missed object
            continue
        pts = point_of[k]
        keep = pts[rng.random(len(pts)) < rng.uniform(0.5, 1.0)]
        extra = void[rng.integers(0, len(void), int(len(pts) * rng.uniform(0, 0.4)))]
        m = np.zeros(n, bool)
        m[keep] = True
        m[extra] = True
        masks.append(m)
        if rng.random() < 0.2:  # duplicate
            masks.append(m & (rng.random(n) < 0.9))
    while len(masks) < 100:  # blobs on void and fragments
        m = np.zeros(n, bool)
        m[void[rng.integers(0, len(void), int(rng.integers(50, 3000)))]] = True
        masks.append(m)
    scores = rng.random(len(masks)).astype(np.float32)
    return labels, np.stack(masks), scores


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=312)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--io", type=int, default=0, help="also time npz write+read on this many scenes")
    ap.add_argument("--end-to-end", type=Path, default=None, metavar="DIR",
                    help="write the scenes (array format) and predictions (npz) under DIR, then time "
                         "evaluate_dataset on them with 1 and 2 workers (DIR is removed afterwards)")
    args = ap.parse_args()
    if args.end_to_end is not None:
        end_to_end(args)
        return
    rng = np.random.default_rng(args.seed)
    t_gen = t_eval = 0.0
    matches = []
    total_pts = total_pred = 0
    io_write = io_read = 0.0
    tmp = Path(tempfile.mkdtemp(prefix="bench_eval_"))
    for i in range(args.scenes):
        t0 = time.perf_counter()
        inst, masks, scores = synthetic_scene(rng)
        t1 = time.perf_counter()
        matches.append(match_scene(inst, masks, scores, scene_id=f"s{i:03d}"))
        t2 = time.perf_counter()
        t_gen += t1 - t0
        t_eval += t2 - t1
        total_pts += len(inst)
        total_pred += len(masks)
        if i < args.io:
            p = tmp / f"s{i:03d}.npz"
            save_predictions(p, masks, scores)
            t3 = time.perf_counter()
            load_predictions(p, len(inst))
            io_write += t3 - t2
            io_read += time.perf_counter() - t3
    t0 = time.perf_counter()
    result = summarize(matches)
    t_sum = time.perf_counter() - t0
    print(f"scenes {args.scenes}, points {total_pts:,}, predictions {total_pred:,}")
    print(f"matching {t_eval:.2f} s ({1000 * t_eval / args.scenes:.1f} ms/scene), pooled AP/AR {t_sum:.3f} s, "
          f"evaluation total {t_eval + t_sum:.2f} s (data synthesis {t_gen:.1f} s, not counted)")
    print("AP %.3f AP50 %.3f AP25 %.3f AR %.3f AR50 %.3f AR25 %.3f" % tuple(result[k] for k in ("AP", "AP50", "AP25", "AR", "AR50", "AR25")))
    if args.io:
        print(f"npz write {1000 * io_write / args.io:.0f} ms/scene, read {1000 * io_read / args.io:.0f} ms/scene "
              f"(mean of {args.io}); size {sum(f.stat().st_size for f in tmp.glob('*.npz')) / args.io / 1e6:.2f} MB/scene")
    for f in tmp.glob("*.npz"):
        f.unlink()
    tmp.rmdir()


def end_to_end(args: argparse.Namespace) -> None:
    import shutil

    from assist3d.data import open_dataset
    from assist3d.bench.evaluation import evaluate_dataset

    rng = np.random.default_rng(args.seed)
    gt, pred = args.end_to_end / "gt", args.end_to_end / "pred"
    gt.mkdir(parents=True, exist_ok=False)
    for i in range(args.scenes):
        inst, masks, scores = synthetic_scene(rng)
        a = np.zeros((len(inst), 8), np.float32)
        a[:, :3] = rng.random((len(inst), 3), dtype=np.float32) * 5
        a[:, 6] = np.where(inst >= 0, 5, 1)  # objects: chair, the rest: wall
        a[:, 7] = np.where(inst >= 0, inst + 1, 0)
        np.save(gt / f"scene{i:04d}_00.npy", a)
        save_predictions(pred / f"scene{i:04d}_00.npz", masks, scores)
    try:
        ds = open_dataset(f"array:{gt}")
        for workers in (1, 2):
            t0 = time.perf_counter()
            r = evaluate_dataset(ds, pred, workers=workers)
            dt = time.perf_counter() - t0
            print(f"evaluate_dataset, {len(ds)} scenes, workers {workers}: {dt:.1f} s "
                  f"(AP {r.overall['AP']:.3f}, AP50 {r.overall['AP50']:.3f})")
    finally:
        shutil.rmtree(args.end_to_end)


if __name__ == "__main__":
    main()
