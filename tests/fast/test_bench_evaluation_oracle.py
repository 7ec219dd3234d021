"""The vectorised evaluation against a plain, object-by-object restatement of the benchmark rules.

The oracle below walks GT objects and predictions with dicts and Python lists the way the
benchmark script's procedure is described (see docs/evaluation.md), without any of the
vectorisation; random scenes with overlapping, duplicated, tiny, void-heavy and tied predictions
must give identical per-threshold AP and recall, per scene and pooled.
"""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.bench.evaluation import ALL_THRESHOLDS, match_scene, summarize

MIN = 100


def oracle_scene(instance, masks, scores):
    gts = []
    for gid in sorted(set(instance[instance >= 0].tolist())):
        gts.append({"id": gid, "size": int((instance == gid).sum()), "matched_pred": []})
    preds = []
    order = sorted(range(len(masks)), key=lambda i: (-float(scores[i]), i))
    for i in order:
        size = int(masks[i].sum())
        if size < MIN:
            continue
        p = {"name": i, "size": size, "conf": float(scores[i]),
             "void": int((masks[i] & (instance < 0)).sum()), "matched_gt": []}
        for g in gts:
            inter = int((masks[i] & (instance == g["id"])).sum())
            if inter > 0:
                g["matched_pred"].append({**p, "inter": inter})
                p["matched_gt"].append({**g, "inter": inter})
        preds.append(p)
    out = []
    for th in ALL_THRESHOLDS:
        visited = {p["name"]: False for p in preds}
        y_true, y_score, hard_fn, matched_ids = [], [], 0, []
        for g in gts:
            if g["size"] < MIN:
                continue
            cur_match, cur_score = False, -np.inf
            for p in g["matched_pred"]:
                if visited[p["name"]]:
                    continue
                iou = p["inter"] / (g["size"] + p["size"] - p["inter"])
                if iou > th:
                    if cur_match:
                        y_true.append(0)
                        y_score.append(min(cur_score, p["conf"]))
                        cur_score = max(cur_score, p["conf"])
                    else:
                        cur_match, cur_score = True, p["conf"]
                        visited[p["name"]] = True
            if cur_match:
                y_true.append(1)
                y_score.append(cur_score)
                matched_ids.append(g["id"])
            else:
                hard_fn += 1
        for p in preds:
            if any(gm["inter"] / (gm["size"] + p["size"] - gm["inter"]) > th for gm in p["matched_gt"]):
                continue
            ignore = p["void"] + sum(gm["inter"] for gm in p["matched_gt"] if gm["size"] < MIN)
            if ignore / p["size"] <= th:
                y_true.append(0)
                y_score.append(p["conf"])
        out.append((y_true, y_score, hard_fn, matched_ids))
    n_gt = sum(1 for g in gts if g["size"] >= MIN)
    return out, n_gt, len(preds)


def oracle_ap(y_true, y_score, hard_fn, has_gt, has_pred):
    if not has_gt:
        return float("nan")
    if not has_pred:
        return 0.0
    pairs = sorted(zip(y_score, y_true), key=lambda t: t[0])
    scores_sorted = [s for s, _ in pairs]
    trues = [t for _, t in pairs]
    n, n_true = len(pairs), sum(trues)
    uniq_first = [i for i in range(n) if i == 0 or scores_sorted[i] != scores_sorted[i - 1]]
    prec, rec = [], []
    for i in uniq_first:
        before = sum(trues[:i])
        tp = n_true - before
        fp = n - i - tp
        fn = before + hard_fn
        prec.append(tp / (tp + fp))
        rec.append(tp / (tp + fn))
    prec.append(1.0)
    rec.append(0.0)
    r = [rec[0]] + rec + [0.0]
    return sum(prec[i] * (r[i] - r[i + 2]) / 2 for i in range(len(prec)))


def random_scene(rng):
    n = int(rng.integers(1500, 3000))
    g = int(rng.integers(0, 9))
    inst = np.full(n, -1, np.int32)
    pos = 0
    for k in range(g):
        size = int(rng.choice([40, 90, 100, 150, 250, 400]))
        inst[pos:pos + size] = k * 3 + 1  # non-contiguous ids
        pos += size
    inst = inst[rng.permutation(n)]
    masks = []
    for _ in range(int(rng.integers(0, 14))):
        kind = rng.integers(0, 4)
        m = np.zeros(n, bool)
        if kind < 2 and g:  # noisy copy of one or two objects
            for k in rng.choice(g, size=int(rng.integers(1, 3))):
                pts = np.flatnonzero(inst == k * 3 + 1)
                m[pts[rng.random(len(pts)) < rng.uniform(0.3, 1.0)]] = True
        if kind >= 1:  # some void or random points
            m[rng.integers(0, n, int(rng.integers(0, 300)))] = True
        masks.append(m)
        if rng.random() < 0.3:
            masks.append(m & (rng.random(n) < 0.95))
    masks = np.stack(masks) if masks else np.zeros((0, n), bool)
    scores = np.round(rng.random(len(masks)), 1).astype(np.float32)  # many ties
    return inst, masks, scores


@pytest.mark.parametrize("seed", range(6))
def test_matches_the_object_by_object_oracle(seed):
    rng = np.random.default_rng(seed)
    scenes = [random_scene(rng) for _ in range(8)]
    ours = [match_scene(i, m, s, scene_id=str(k)) for k, (i, m, s) in enumerate(scenes)]
    oracle = [oracle_scene(i, m, s) for i, m, s in scenes]
    for mine, (per_t, n_gt, n_pred) in zip(ours, oracle):
        m = summarize([mine])
        for t in range(len(ALL_THRESHOLDS)):
            yt, ys, fn, ids = per_t[t]
            assert sorted(mine.gt_ids[mine.gt_matched[t]].tolist()) == sorted(ids)
            np.testing.assert_allclose(m.ap[t], oracle_ap(yt, ys, fn, n_gt > 0, n_pred > 0), equal_nan=True)
    pooled = summarize(ours)
    total_gt = sum(o[1] for o in oracle)
    total_pred = sum(o[2] for o in oracle)
    for t in range(len(ALL_THRESHOLDS)):
        yt = [y for o in oracle for y in o[0][t][0]]
        ys = [y for o in oracle for y in o[0][t][1]]
        fn = sum(o[0][t][2] for o in oracle)
        np.testing.assert_allclose(pooled.ap[t], oracle_ap(yt, ys, fn, total_gt > 0, total_pred > 0), equal_nan=True)
