"""Hungarian matching of predicted masks to ground-truth instances (scipy ``linear_sum_assignment``).

cost(q, g) = w_obj * (-sigmoid(objectness_q)) + w_mask * BCE(mask_q, gt_g) + w_dice * dice(mask_q, gt_g),
BCE averaged over the voxels, dice = 1 - (2 sum(p t) + 1) / (sum(p) + sum(t) + 1).
"""

from __future__ import annotations

import numpy as np
import torch
import torch.nn.functional as F
from scipy.optimize import linear_sum_assignment


def pairwise_bce(logits: torch.Tensor, targets: torch.Tensor) -> torch.Tensor:
    """Mean BCE over points of every (prediction, target) pair: logits (N, Q), targets (N, G) -> (Q, G)."""
    n = logits.shape[0]
    pos = F.softplus(-logits)  # -log sigmoid(x)
    neg = F.softplus(logits)  # -log(1 - sigmoid(x))
    return (pos.T @ targets + neg.T @ (1 - targets)) / max(n, 1)


def pairwise_dice(logits: torch.Tensor, targets: torch.Tensor) -> torch.Tensor:
    """Dice loss of every pair: logits (N, Q), targets (N, G) -> (Q, G)."""
    p = logits.sigmoid()
    inter = p.T @ targets
    return 1 - (2 * inter + 1) / (p.sum(0)[:, None] + targets.sum(0)[None, :] + 1)


def match_cost(obj_logits: torch.Tensor, mask_logits: torch.Tensor, targets: torch.Tensor,
               w_obj: float = 2.0, w_mask: float = 5.0, w_dice: float = 2.0) -> torch.Tensor:
    """Cost matrix (Q, G) for ``obj_logits`` (Q,), ``mask_logits`` (N, Q), ``targets`` (N, G) float 0/1."""
    logits = mask_logits.float()
    t = targets.float()
    return (w_obj * -obj_logits.float().sigmoid()[:, None] + w_mask * pairwise_bce(logits, t)
            + w_dice * pairwise_dice(logits, t))


@torch.no_grad()
def hungarian_match(obj_logits: torch.Tensor, mask_logits: torch.Tensor, targets: torch.Tensor,
                    w_obj: float = 2.0, w_mask: float = 5.0, w_dice: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Optimal one-to-one assignment: ``(query_rows, target_cols)`` int64 arrays of length min(Q, G)."""
    if targets.shape[1] == 0 or mask_logits.shape[1] == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    cost = match_cost(obj_logits, mask_logits, targets, w_obj, w_mask, w_dice).cpu().numpy()
    rows, cols = linear_sum_assignment(cost)
    return rows.astype(np.int64), cols.astype(np.int64)
