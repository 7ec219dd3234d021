"""Copy a trained segmenter into the package as the shipped model (float16 or int8 weights, <= 20 MB).

    python scripts/ship_model.py PROBE_DIR/seed_K/model.pt [--precision float16|int8] [--note TEXT]

Refuses a model whose training sets are not all generated (``assist3d:`` specs): the shipped model
is trained on generated data only. Records the training sets, steps and seconds in its metadata.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from assist3d.learn.segmenter.checkpoint import load_segmenter, save_segmenter
from assist3d.learn.segmenter.shipped import SHIPPED_NAME

LIMIT = 20 * 1024 * 1024  # issue 51: at most 20 MB in the package


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("model", type=Path)
    ap.add_argument("--note", default="")
    ap.add_argument("--precision", choices=("float16", "int8"), default="float16",
                    help="int8: blockwise int8 weights, for a network whose float16 file is over the cap")
    args = ap.parse_args()
    loaded = load_segmenter(args.model)
    train = loaded.meta.get("train", [])
    if not train or not all(str(s).startswith("assist3d:") for s in train):
        raise SystemExit(f"{args.model}: trained on {train}; the shipped model must be trained on generated data only")
    meta = {"train_data": "generated only", "train": [Path(s.split(':', 1)[1]).name for s in train],
            "steps": loaded.meta.get("step"), "train_seconds": loaded.meta.get("train_seconds"),
            "seed": loaded.meta.get("seed"), "precision": args.precision, "note": args.note}
    dest = Path(__file__).resolve().parents[1] / "src" / "assist3d" / "resources" / "models" / SHIPPED_NAME
    dest.parent.mkdir(parents=True, exist_ok=True)
    save_segmenter(dest, loaded.model, loaded.config, meta=meta, precision=args.precision)
    size = dest.stat().st_size
    if size > LIMIT:
        dest.unlink()
        raise SystemExit(f"{dest}: {size} bytes, over the 20 MB limit; shrink the net or use --precision int8")
    print(f"{dest}: {size / 1e6:.2f} MB, {meta}")


if __name__ == "__main__":
    main()
