"""experiments/tools/proposal_scorer.py: the classification of predictions behind the "what limits hybrid AP50"
figures of experiments/fidelity-log.md, and the scorer's fit."""

from __future__ import annotations

import numpy as np
import pytest
import torch


def test_classify_names_every_kind_of_prediction(load_script):
    ps = load_script("proposal_scorer")
    # 1,000 points: object 0 on 0-299, object 1 on 300-599, void beyond
    inst = np.full(1000, -1)
    inst[:300], inst[300:600] = 0, 1
    masks = np.zeros((6, 1000), bool)
    masks[0, :280] = True        # true positive (IoU 0.93)
    masks[1, 10:290] = True      # same object again: duplicate
    masks[2, 300:420] = True     # 40 % of object 1, all on it: partial
    masks[3, 150:480] = True     # half of each object: merge
    masks[4, 600:900] = True     # void: ignored
    masks[5, 520:720] = True     # 80 points on object 1, 120 on void -> ignored (more than half void)
    scores = np.array([0.9, 0.8, 0.7, 0.6, 0.5, 0.4])
    assert ps.classify(masks, scores, inst) == {"true_positive": 1, "ignored": 2, "duplicate": 1, "merge": 1,
                                                "partial": 1, "other": 0}
    # score order decides which of two overlapping masks is the true positive
    out = ps.classify(masks[:2], np.array([0.1, 0.9]), inst)
    assert out["true_positive"] == 1 and out["duplicate"] == 1


def test_best_iou_skips_objects_under_100_points(load_script):
    ps = load_script("proposal_scorer")
    inst = np.full(500, -1)
    inst[:200], inst[200:260] = 0, 1   # object 1 has 60 points: not an object for the protocol
    masks = np.zeros((2, 500), bool)
    masks[0, :100] = True
    masks[1, 200:260] = True
    assert np.allclose(ps.best_iou(masks, inst), [0.5, 0.0])


@pytest.mark.slow
def test_scorer_fit_ranks_by_the_target(load_script):
    ps = load_script("proposal_scorer")
    rng = np.random.default_rng(0)
    feats = rng.normal(size=(400, ps.NUM_FEATURES))
    iou = 1 / (1 + np.exp(-2 * feats[:, 0]))  # the target depends on the first feature only
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        scorer = ps.fit(feats, iou, iters=300)
    finally:
        torch.set_num_threads(threads)
    pred = scorer.score(feats)
    assert np.corrcoef(pred, iou)[0, 1] > 0.95
