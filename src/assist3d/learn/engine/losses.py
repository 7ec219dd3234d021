"""Set-prediction losses of the class-agnostic Mask3D: objectness BCE, mask BCE and dice.

Per decoder layer and scene: match predictions to targets (:func:`hungarian_match`), then
objectness BCE over all queries (target 1 for matched queries, 0 otherwise; unmatched queries weighted
``no_object_weight``, weighted mean), mask BCE (mean over voxels) and dice summed over matched pairs
and divided by the number of targets. Total = w_obj * obj + w_mask * bce + w_dice * dice, summed over
the final layer and (optionally) every auxiliary layer.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F

from ..models.decoder import LayerPrediction
from .config import LossConfig
from .matcher import hungarian_match


@dataclass
class LossParts:
    total: torch.Tensor
    objectness: torch.Tensor
    mask_bce: torch.Tensor
    dice: torch.Tensor


def layer_loss(pred: LayerPrediction, targets: torch.Tensor, cfg: LossConfig) -> LossParts:
    """Loss of one layer's prediction for one scene; ``targets`` (N, G) float 0/1 over the scene's voxels."""
    obj = pred.objectness.float()
    masks = pred.masks.float()
    rows, cols = hungarian_match(obj, masks, targets, cfg.objectness_weight, cfg.mask_weight, cfg.dice_weight)
    q = obj.shape[0]
    obj_target = torch.zeros(q, device=obj.device)
    weight = torch.full((q,), cfg.no_object_weight, device=obj.device)
    if len(rows):
        r = torch.as_tensor(rows, device=obj.device)
        obj_target[r] = 1.0
        weight[r] = 1.0
    obj_loss = (F.binary_cross_entropy_with_logits(obj, obj_target, reduction="none") * weight).sum() / weight.sum()
    n_targets = max(targets.shape[1], 1)
    if len(rows):
        r = torch.as_tensor(rows, device=obj.device)
        c = torch.as_tensor(cols, device=obj.device)
        x = masks[:, r]
        t = targets[:, c].float()
        bce = F.binary_cross_entropy_with_logits(x, t, reduction="none").mean(0).sum() / n_targets
        p = x.sigmoid()
        dice = (1 - (2 * (p * t).sum(0) + 1) / (p.sum(0) + t.sum(0) + 1)).sum() / n_targets
    else:
        bce = masks.sum() * 0.0
        dice = masks.sum() * 0.0
    total = cfg.objectness_weight * obj_loss + cfg.mask_weight * bce + cfg.dice_weight * dice
    return LossParts(total=total, objectness=obj_loss.detach(), mask_bce=bce.detach(), dice=dice.detach())


def scene_loss(preds: list[LayerPrediction], targets: torch.Tensor, cfg: LossConfig,
               sample: torch.Tensor | None = None) -> LossParts:
    """Final-layer loss plus auxiliary losses of earlier layers (each with its own matching).

    ``sample`` (optional, (S,) int64) restricts matching and losses to those voxel rows.
    """
    layers = preds if cfg.aux else preds[-1:]
    if sample is not None:
        targets = targets[sample]
    parts = []
    for p in layers:
        if sample is not None:
            p = LayerPrediction(objectness=p.objectness, masks=p.masks[sample])
        parts.append(layer_loss(p, targets, cfg))
    final = parts[-1]
    return LossParts(total=torch.stack([x.total for x in parts]).sum(), objectness=final.objectness,
                     mask_bce=final.mask_bce, dice=final.dice)
