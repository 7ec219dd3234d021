"""plan.md's measurement: the network's own instances with and without test-time augmentation, per real scan.

    PYTHONPATH=src python experiments/tta-learned-2026-12-08/run.py MODEL.pt OUT.json [--eval SPEC ...]

Both sides are `probe.evaluate_model` (the figures `probe` stores); the TTA side is a post-processing step registered
here, so nothing in the package changes for the measurement.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from assist3d.learn.segmenter.infer import segment_points
from assist3d.learn.segmenter.predictor import STEPS, Step
from assist3d.learn.segmenter.probe import evaluate_model

SPECS = ["array:../shared/data/real/dev", "array:../shared/data/real/scannet_scene0451_01.npy"]
VARIANT = "learned-tta"
PLAIN = "learned-timed"


def timed(tta: bool, seconds: list[float]) -> Step:
    """The network's own instances (`segment --method learned`, with or without `--tta`), each call's seconds kept."""
    def run(model, cfg, coord, color, **_):  # the predictor passes its own tta flag; this step fixes it
        t0 = time.perf_counter()
        seg = segment_points(model, cfg, coord, color, tta=tta)
        seconds.append(round(time.perf_counter() - t0, 2))
        return seg

    return Step(run)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("model", type=Path)
    ap.add_argument("out", type=Path)
    ap.add_argument("--eval", action="append", help="reader specs (default: the dev scans and scene0451_01)")
    a = ap.parse_args()
    result: dict[str, object] = {"model": str(a.model)}
    with tempfile.TemporaryDirectory() as tmp:
        for method, tta in ((PLAIN, False), (VARIANT, True)):
            seconds: list[float] = []
            STEPS.add(method, timed(tta, seconds))
            res = evaluate_model(a.model, a.eval or SPECS, Path(tmp) / method, method=method)
            res["network_seconds"] = dict(zip(res["per_scene"], seconds))  # per_scene keeps the order scans ran in
            print(method, {k: res[k] for k in ("AP", "AP50", "AP25", "predict_seconds")}, flush=True)
            result[method] = res
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
