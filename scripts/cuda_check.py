"""Exercise the CUDA paths on a GPU machine and write what they did to one JSON file.

The CPU is where this project is developed and tested; this script is the check of the GPU code
paths, run when a GPU is at hand (docs/model.md, "CUDA check"):

- Mask3D-style model: the first loss on the same batch and weights on the CPU and on CUDA (fp32),
  then training steps with AMP in bf16, in fp16 with the gradient scaler (bf16 reported as
  unsupported to reach that branch) and in fp32; the loss must fall and stay finite;
  ``train()`` to a checkpoint on CUDA, resumed for one more epoch; ``predict_scene`` on CUDA against the CPU
  with the same weights; ``run_model_bench`` on CUDA (forward, forward+backward, peak memory).
  After 150 fp32 training steps (so that masks exist) ``predict_scene`` and the final mask logits on
  CUDA against the CPU; the fp16 gradient scaler saved in a checkpoint, read back and restored; fp16
  training resumed from a checkpoint written after real optimiser steps, against the run that wrote it.
- CPU segmenter: the shipped model's per-voxel outputs on a real scan on the CPU and on CUDA,
  ``segment_hybrid`` on both (instances, AP50 against the scan's labels, seconds), and training
  steps on CUDA (the loss must fall); its training interrupted and resumed from last.pt.

    python scripts/cuda_check.py --scan SCAN.npy --out report.json [--steps 60] [--only SECTION ...]

Every section runs even when another fails; a failure is recorded with its traceback.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np
import torch

from assist3d.learn.engine.config import parse_train_config
from assist3d.learn.engine.toy import make_toy_scene
from assist3d.learn.engine.train import MemorySource, Trainer

DEV = "cuda"  # --device cpu runs the same sections on the CPU: a dry run of this script where there is no GPU

MODEL = {"stem_channels": 16, "stem_kernel": 3, "enc_channels": [16, 32, 64, 96], "enc_blocks": [1, 1, 1, 1],
         "dec_channels": [96, 64, 48, 48], "dec_blocks": [1, 1, 1, 1], "hidden": 64, "heads": 4, "ffn": 256,
         "num_passes": 2, "num_queries": 32, "num_queries_eval": 32}


def _cfg(**optim) -> dict:
    return {"threads": 4, "seed": 0, "model": MODEL, "data": {"voxel_size": 0.05}, "augment": {"enabled": False},
            "optim": {"lr": 0.003, "batch_size": 2, "epochs": 2, "pct_start": 0.3, **optim}, "predict": {"top_k": 32}}


def _toy(n: int) -> list:
    return [make_toy_scene(f"toy{i}", rng=np.random.default_rng(i), num_objects=6, room_m=5.0, density_per_m2=2500.0)
            for i in range(n)]


def _sync() -> None:
    if torch.cuda.is_available():
        torch.cuda.synchronize()


def _trainer(cfg, scenes: list, steps: int, *, fp16: bool = False) -> Trainer:
    """A Trainer on DEV; ``fp16`` reports bf16 as unsupported on CUDA to reach the fp16 + GradScaler branch."""
    real = torch.cuda.is_bf16_supported
    if fp16 and DEV == "cuda":
        torch.cuda.is_bf16_supported = lambda *a, **k: False
    try:
        return Trainer(cfg, MemorySource(scenes), steps_total=steps, device=DEV)
    finally:
        torch.cuda.is_bf16_supported = real


def mask3d_first_loss_parity() -> dict:
    cfg = parse_train_config(_cfg())
    scenes = _toy(2)
    out = {}
    for dev in ("cpu", DEV):
        tr = Trainer(cfg, MemorySource(scenes), steps_total=10, device=dev)
        tr.model.eval()
        with torch.no_grad():
            loss, _ = tr.batch_loss([0, 1], rng=np.random.default_rng(0), augment=False)
        out[dev] = float(loss)
    out["abs_diff"] = abs(out["cpu"] - out[DEV])
    out["ok"] = out["abs_diff"] <= 1e-3 * max(1.0, abs(out["cpu"]))
    return out


def mask3d_amp_training(steps: int) -> dict:
    scenes = _toy(4)
    res = {}
    for mode in ("bf16", "fp16", "fp32"):
        cfg = parse_train_config(_cfg(amp=mode != "fp32"))
        tr = _trainer(cfg, scenes, steps, fp16=mode == "fp16")
        rng = np.random.default_rng(0)
        losses = []
        _sync()
        t0 = time.perf_counter()
        for s in range(steps):
            idx = [int(i) for i in rng.choice(len(scenes), 2, replace=False)]
            st = tr.step(idx, rng=np.random.default_rng(s))
            losses.append(float(st.loss))
        _sync()
        sec = (time.perf_counter() - t0) / steps
        first, last = float(np.mean(losses[:5])), float(np.mean(losses[-5:]))
        res[mode] = {"amp": tr.use_amp, "dtype": str(tr.amp_dtype) if tr.use_amp else "float32",
                     "scaler": tr.scaler is not None, "scale": float(tr.scaler.get_scale()) if tr.scaler else None,
                     "loss_first5": round(first, 4), "loss_last5": round(last, 4), "finite": bool(np.isfinite(losses).all()),
                     "seconds_per_step": round(sec, 4), "ok": bool(np.isfinite(losses).all() and last < first)}
    return res


def mask3d_train_resume_predict(tmp: Path) -> dict:
    from assist3d.learn.engine.predict import predict_scene
    from assist3d.learn.engine.train import build_model, config_from_checkpoint, load_checkpoint, train

    scenes = _toy(4)
    out = tmp / "m3d"
    cfg = parse_train_config({**_cfg(epochs=2), "device": DEV})
    r1 = train(cfg, out, source=MemorySource(scenes))
    cfg3 = parse_train_config({**_cfg(epochs=3), "device": DEV})
    r2 = train(cfg3, out, resume=True, source=MemorySource(scenes))
    state = load_checkpoint(out / "last.pt", map_location="cpu")
    tcfg = config_from_checkpoint(state)
    preds = {}
    for dev in ("cpu", DEV):
        model = build_model(tcfg.model)
        model.load_state_dict(state["model"])
        model.to(dev).eval()
        with torch.no_grad():
            preds[dev] = predict_scene(model, scenes[0], tcfg.data.voxel_size, tcfg.predict, device=dev)
    a, b = preds["cpu"], preds[DEV]
    n = min(len(a.scores), len(b.scores))
    agree = float((a.masks[:n] == b.masks[:n]).mean()) if n else None
    return {"steps_first": r1.steps, "steps_after_resume": r2.steps, "last_loss": r2.last_loss,
            "masks_cpu": int(len(a.scores)), "masks_cuda": int(len(b.scores)),
            "mask_point_agreement": agree, "max_score_diff": float(np.abs(a.scores[:n] - b.scores[:n]).max()) if n else None,
            # no mask on either device shows nothing about agreement: ok is then None, not True
            "ok": (None if n == 0 and len(a.scores) == len(b.scores) and r2.steps > r1.steps
                   else bool(r2.steps > r1.steps and np.isfinite(r2.last_loss) and len(a.scores) == len(b.scores)
                             and agree is not None and agree > 0.99))}


def mask3d_predict_parity(steps: int) -> dict:
    """The same trained weights on the CPU and on CUDA: final mask logits and ``predict_scene``'s masks.

    Trained in fp32 on CUDA for ``steps`` steps first, so that the model predicts masks at all (after a few
    steps every logit is negative and ``predict_scene`` returns nothing to compare).
    """
    from assist3d.learn.engine.predict import predict_scene
    from assist3d.learn.engine.train import build_model
    from assist3d.learn.engine.voxelize import collate, voxelize

    scenes = _toy(4)
    cfg = parse_train_config(_cfg(amp=False))
    tr = Trainer(cfg, MemorySource(scenes), steps_total=steps, device=DEV)
    rng = np.random.default_rng(0)
    for s in range(steps):
        idx = [int(i) for i in rng.choice(len(scenes), 2, replace=False)]
        tr.step(idx, rng=np.random.default_rng(s))
    state = {k: v.detach().cpu().clone() for k, v in tr.model.state_dict().items()}
    logits, preds = {}, {}
    for dev in ("cpu", DEV):
        m = build_model(cfg.model)
        m.load_state_dict(state)
        m.to(dev).eval()
        with torch.no_grad():
            vox = voxelize(scenes[0].coord, scenes[0].color, None, cfg.data.voxel_size)
            coords, feats = collate([vox], dev)
            logits[dev] = m(coords, feats, 1)[0][-1].masks.float().cpu().numpy()
            preds[dev] = predict_scene(m, scenes[0], cfg.data.voxel_size, cfg.predict, device=dev)
    a, b = preds["cpu"], preds[DEV]
    diff = float(np.abs(logits["cpu"] - logits[DEV]).max())
    scale = float(np.abs(logits["cpu"]).max())
    n = min(len(a.scores), len(b.scores))
    agree = float((a.masks[:n] == b.masks[:n]).mean()) if n else None
    return {"steps": steps, "logit_max_abs_diff": diff, "logit_max_abs": scale,
            "masks_cpu": int(len(a.scores)), "masks_cuda": int(len(b.scores)), "mask_point_agreement": agree,
            "max_score_diff": float(np.abs(a.scores[:n] - b.scores[:n]).max()) if n else None,
            # no mask shows nothing about predict_scene's agreement: ok is then None, not True
            "ok": (None if len(a.scores) == len(b.scores) == 0 else bool(len(a.scores) == len(b.scores) and agree is not None and agree > 0.99
                                            and diff <= 1e-2 * max(1.0, scale)))}


def mask3d_fp16_scaler_resume(tmp: Path) -> dict:
    """fp16 with the gradient scaler: its state saved in a checkpoint, read back with ``weights_only`` and restored."""
    from assist3d.learn.engine.train import load_checkpoint, save_checkpoint

    scenes = _toy(4)
    cfg = parse_train_config(_cfg(amp=True))
    tr = _trainer(cfg, scenes, 20, fp16=True)
    if tr.scaler is None:
        return {"ok": None, "reason": f"no gradient scaler on {DEV} (fp16 AMP is CUDA-only)"}
    for s in range(5):
        tr.step([s % 4, (s + 1) % 4], rng=np.random.default_rng(s))
    saved = tr.scaler.state_dict()
    path = tmp / "fp16.pt"
    tmp.mkdir(parents=True, exist_ok=True)
    save_checkpoint(path, tr.model, tr.optimizer, tr.scheduler, 1, 5, cfg, tr.scaler)
    state = load_checkpoint(path, map_location=DEV)
    tr2 = _trainer(cfg, scenes, 20, fp16=True)
    fresh = float(tr2.scaler.get_scale())  # before the restore: what a scaler starts with
    tr2.restore(state)
    restored = tr2.scaler.state_dict()
    st = tr2.step([0, 1], rng=np.random.default_rng(5))
    same = {k: restored.get(k) == v for k, v in saved.items()}
    return {"saved": {k: float(v) for k, v in saved.items()}, "restored": {k: float(v) for k, v in restored.items()},
            "fresh_scale": fresh, "loss_after_resume": float(st.loss),
            "ok": bool(all(same.values()) and np.isfinite(st.loss))}


def _max_param_diff(a: torch.nn.Module, b: torch.nn.Module) -> float:
    sa, sb = a.state_dict(), b.state_dict()
    return max(float((sa[k].float() - sb[k].float()).abs().max()) for k in sa if sa[k].numel())


def mask3d_fp16_resume_equivalence(tmp: Path, warm: int = 30, after: int = 3) -> dict:
    """fp16 + gradient scaler, resumed from a checkpoint written after steps that were *not* skipped.

    ``warm`` steps first, so that the scaler settles below overflow and the optimiser really steps (the
    growth tracker counts steps since the last overflow); then a checkpoint, ``after`` more steps on the
    trainer that wrote it, and the same ``after`` steps (same batches and random streams) on a fresh
    trainer restored from the file. The two must agree (losses and weights) as closely as two identical
    runs on this device do, and much closer than a control restored with the weights alone (fresh
    optimiser moments and scaler), which shows that the check can fail.
    """
    from assist3d.learn.engine.train import load_checkpoint, save_checkpoint

    scenes = _toy(4)
    cfg = parse_train_config(_cfg(amp=True))
    total = warm + after + 4

    def new():
        tr = _trainer(cfg, scenes, total, fp16=True)
        if tr.scaler is None and DEV == "cpu":  # dry run: a CPU scaler exercises the same state handling
            tr.scaler = torch.amp.GradScaler("cpu")
        return tr

    def go(tr, first: int, n: int) -> list[float]:
        return [float(tr.step([s % 4, (s + 1) % 4], rng=np.random.default_rng(s)).loss)
                for s in range(first, first + n)]

    tr = new()
    if tr.scaler is None:
        return {"ok": None, "reason": f"no gradient scaler on {DEV} (fp16 AMP is CUDA-only)"}
    scales = []
    for s in range(warm):
        go(tr, s, 1)
        scales.append(float(tr.scaler.get_scale()))
    saved = {k: float(v) for k, v in tr.scaler.state_dict().items()}
    adam_steps = [float(st["step"]) for st in tr.optimizer.state_dict()["state"].values() if "step" in st]
    tmp.mkdir(parents=True, exist_ok=True)
    path = tmp / "fp16_equiv.pt"
    save_checkpoint(path, tr.model, tr.optimizer, tr.scheduler, 1, warm, cfg, tr.scaler)
    loss_cont = go(tr, warm, after)
    state = load_checkpoint(path, map_location=DEV)
    res = new()
    res.restore(state)
    restored = {k: float(v) for k, v in res.scaler.state_dict().items()}
    loss_res = go(res, warm, after)
    # the noise floor: the same checkpoint restored a second time, the same steps
    twin = new()
    twin.restore(load_checkpoint(path, map_location=DEV))
    go(twin, warm, after)
    # the control: weights only, fresh optimiser moments, schedule and scaler
    ctl = new()
    ctl.model.load_state_dict(state["model"])
    loss_ctl = go(ctl, warm, after)
    d_res, d_twin, d_ctl = (_max_param_diff(tr.model, t.model) for t in (res, twin, ctl))
    real_steps = int(min(adam_steps)) if adam_steps else 0
    return {"warm_steps": warm, "scales": scales, "saved": saved, "restored": restored,
            "optimizer_steps_taken_before_save": real_steps,
            "loss_continued": loss_cont, "loss_resumed": loss_res, "loss_weights_only_control": loss_ctl,
            "param_diff_resumed": d_res, "param_diff_twin_restore": d_twin, "param_diff_control": d_ctl,
            "ok": bool(real_steps > 0 and saved == restored and np.isfinite(loss_res).all()
                       and d_res <= max(10 * d_twin, 1e-6) and d_ctl > 10 * max(d_res, 1e-7))}


def mask3d_bench() -> dict:
    from assist3d.learn.engine.bench import run_model_bench
    from assist3d.learn.engine.config import TrainConfig

    out = {}
    for dev in (DEV,):
        r = run_model_bench(TrainConfig(), points=100_000, device=dev, repeats=3)
        out[dev] = {k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.as_dict().items()}
    return out


def segmenter_shipped(scan: Path) -> dict:
    from assist3d.data.array import ArrayDataset
    from assist3d.bench.evaluation.ap import match_scene, summarize
    from assist3d.learn.segmenter.checkpoint import load_segmenter
    from assist3d.learn.segmenter.hybrid import segment_hybrid
    from assist3d.learn.segmenter.infer import predict_voxels
    from assist3d.learn.segmenter.shipped import shipped_model_path
    from assist3d.learn.segmenter.features import voxel_features, voxelize

    s = ArrayDataset(scan).load(scan.stem)
    res: dict = {"scan": scan.name, "points": int(len(s.coord))}
    outs = {}
    for dev in ("cpu", DEV):
        loaded = load_segmenter(shipped_model_path(), dev)
        cfg = loaded.config
        vox = voxelize(s.coord, cfg.net.voxel_size, s.color)
        with torch.no_grad():
            fg, off = predict_voxels(loaded.model, vox.coords, voxel_features(vox, use_color=cfg.net.use_color), dev)
        _sync()
        t0 = time.perf_counter()
        seg = segment_hybrid(loaded.model, cfg, s.coord, s.color, device=dev)
        _sync()
        sec = time.perf_counter() - t0
        m = summarize([match_scene(s.instance, seg.masks, seg.scores, valid=s.valid, scene_id=scan.stem)])
        outs[dev] = (fg, off, seg)
        res[dev] = {"instances": int(len(seg.scores)), "AP50": round(float(m["AP50"]), 4),
                    "AP25": round(float(m["AP25"]), 4), "seconds": round(sec, 2)}
    (fc, oc, sc), (fg_, og, sg) = outs["cpu"], outs[DEV]
    res["fg_max_abs_diff"] = float(np.abs(fc - fg_).max())
    res["offset_max_abs_diff"] = float(np.abs(oc - og).max())
    res["same_instances"] = bool(len(sc.scores) == len(sg.scores) and np.array_equal(sc.masks, sg.masks))
    res["ok"] = bool(res["fg_max_abs_diff"] < 1e-3 and abs(res["cpu"]["AP50"] - res[DEV]["AP50"]) < 0.01)
    return res


def segmenter_training(tmp: Path, steps: int) -> dict:
    from assist3d.learn.segmenter.config import parse_segmenter_config
    from assist3d.learn.segmenter.data import Scene
    from assist3d.learn.segmenter.train import Budget, train_segmenter

    scenes = [Scene.from_sample(x) for x in _toy(6)]
    cfg = parse_segmenter_config({}, "defaults")
    rec = train_segmenter(cfg, scenes, tmp / "seg", seed=0, budget=Budget(steps=steps, minutes=None), device=DEV)
    rows = (tmp / "seg" / "train_log.csv").read_text().splitlines()
    head = rows[0].split(",")
    loss = np.array([float(r.split(",")[head.index("loss")]) for r in rows[1:]])
    k = max(1, min(10, len(loss) // 4))
    first, last = float(loss[:k].mean()), float(loss[-k:].mean())
    return {"steps": int(len(loss)), "loss_first": round(first, 4), "loss_last": round(last, 4),
            "train_seconds": round(rec.train_seconds, 1),
            "ok": bool(np.isfinite(loss).all() and last < first)}


def segmenter_resume(tmp: Path, steps: int = 24, cut: int = 12) -> dict:
    """The segmenter's training interrupted after ``cut`` steps and resumed from last.pt on DEV, against an
    uninterrupted run with the same seed (and a second uninterrupted run: this device's noise floor)."""
    from assist3d.learn.segmenter import train as train_mod
    from assist3d.learn.segmenter.checkpoint import load_segmenter
    from assist3d.learn.segmenter.config import parse_segmenter_config
    from assist3d.learn.segmenter.data import Scene
    from assist3d.learn.segmenter.train import Budget, train_segmenter

    scenes = [Scene.from_sample(x) for x in _toy(6)]
    cfg = parse_segmenter_config({}, "defaults")
    root = tmp / "segresume"
    for name in ("full", "full2"):
        train_segmenter(cfg, scenes, root / name, seed=0, budget=Budget(steps=steps, minutes=None), device=DEV)
    every = train_mod.CHECKPOINT_EVERY_S
    train_mod.CHECKPOINT_EVERY_S = -1.0  # a checkpoint after every step

    def stop(row: dict) -> None:
        if row["step"] == cut + 1:
            raise KeyboardInterrupt

    try:
        try:
            train_segmenter(cfg, scenes, root / "cut", seed=0, budget=Budget(steps=steps, minutes=None), device=DEV,
                            on_step=stop)
        except KeyboardInterrupt:
            pass
    finally:
        train_mod.CHECKPOINT_EVERY_S = every
    at = int(load_segmenter(root / "cut" / "last.pt").progress["step"])
    train_segmenter(cfg, scenes, root / "cut", seed=0, budget=Budget(steps=steps, minutes=None), device=DEV)
    m = {n: load_segmenter(root / n / "last.pt").model for n in ("full", "full2", "cut")}

    def losses(n: str) -> list[float]:
        rows = (root / n / "train_log.csv").read_text().splitlines()
        i = rows[0].split(",").index("loss")
        return [float(r.split(",")[i]) for r in rows[1:]]

    d_cut, d_twin = _max_param_diff(m["full"], m["cut"]), _max_param_diff(m["full"], m["full2"])
    lf, lc = losses("full"), losses("cut")
    return {"steps": steps, "resumed_from_step": at, "logged_steps_cut": len(lc),
            "param_diff_resumed": d_cut, "param_diff_two_full_runs": d_twin,
            "loss_max_abs_diff": float(np.abs(np.array(lf) - np.array(lc)).max()) if len(lf) == len(lc) else None,
            "ok": bool(at == cut and len(lc) == steps and d_cut <= max(10 * d_twin, 1e-5))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scan", type=Path, required=True, help="a real scan (N, 8) .npy with instance labels")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--tmp", type=Path, default=None, help="scratch folder (default: a new temporary one; "
                    "an old one would let training resume from an earlier run)")
    ap.add_argument("--device", default="cuda", help="cuda (the check) or cpu (a dry run of the script)")
    ap.add_argument("--only", nargs="+", default=None, metavar="SECTION", help="run only these sections")
    ap.add_argument("--predict-steps", type=int, default=150,
                    help="fp32 training steps before the predict_scene comparison")
    a = ap.parse_args()
    global DEV
    DEV = a.device
    if a.tmp is None:
        a.tmp = Path(tempfile.mkdtemp(prefix="cuda_check_"))
    if DEV == "cuda" and not torch.cuda.is_available():
        raise SystemExit("no CUDA device: this script checks the GPU paths (--device cpu for a dry run)")
    report: dict = {"torch": torch.__version__, "cuda": torch.version.cuda, "device": DEV,
                    "gpu": torch.cuda.get_device_name(0) if DEV == "cuda" else None}
    sections = [("mask3d_first_loss_parity", mask3d_first_loss_parity),
                ("mask3d_amp_training", lambda: mask3d_amp_training(a.steps)),
                ("mask3d_train_resume_predict", lambda: mask3d_train_resume_predict(a.tmp)),
                ("mask3d_bench", mask3d_bench),
                ("segmenter_shipped", lambda: segmenter_shipped(a.scan)),
                ("segmenter_training", lambda: segmenter_training(a.tmp, a.steps)),
                ("mask3d_predict_parity", lambda: mask3d_predict_parity(a.predict_steps)),
                ("mask3d_fp16_scaler_resume", lambda: mask3d_fp16_scaler_resume(a.tmp)),
                ("mask3d_fp16_resume_equivalence", lambda: mask3d_fp16_resume_equivalence(a.tmp)),
                ("segmenter_resume", lambda: segmenter_resume(a.tmp))]
    if a.only:
        unknown = sorted(set(a.only) - {n for n, _ in sections})
        if unknown:
            raise SystemExit(f"--only: unknown section(s) {', '.join(unknown)}; known: {', '.join(n for n, _ in sections)}")
        sections = [(n, f) for n, f in sections if n in a.only]
    for name, fn in sections:
        t0 = time.perf_counter()
        try:
            report[name] = fn()
        except Exception:  # noqa: BLE001 - a check records every failure and goes on
            report[name] = {"ok": False, "error": traceback.format_exc()[-3000:]}
        report[name]["section_seconds"] = round(time.perf_counter() - t0, 1)
        print(name, json.dumps(report[name])[:600], flush=True)
        a.out.write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
