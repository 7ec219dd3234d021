"""Pack training scenes into one small file, and unpack them as ``array:`` scenes elsewhere.

Used to carry generated datasets to a machine that cannot generate them (for example a lent GPU
machine without the asset library): a 165,000-point scene packs into ~0.3 MB.

    python scripts/pack_scenes.py pack OUT.npz.xz SPEC [SPEC ...] [--exact]
    python scripts/pack_scenes.py unpack IN.npz.xz DIR      # DIR/<spec index>_<scene>.npy, (N, 8) float32

Packing keeps what the segmenter trains on: coordinates (quantised to 2 mm, below the 5-20 mm
training jitter, and sorted, unless ``--exact``) and instance ids (objects keep their id, everything else is
void); colours are kept only with ``--exact`` (the default segmenter is geometry-only). Unpacked
scenes follow the ``array`` reader's convention: semantic 3 (an object class) for object points,
1 (wall) for background, so ``array:DIR`` gives the segmenter the same objects and background.
"""

from __future__ import annotations

import argparse
import io
import lzma
import sys
from pathlib import Path

import numpy as np

STEP = 0.002  # metres per quantisation step


def pack(out: Path, specs: list[str], exact: bool) -> None:
    from assist3d.data import open_dataset

    arrays: dict[str, np.ndarray] = {}
    for k, spec in enumerate(specs):
        for sample in open_dataset(spec):
            key = f"{k:02d}_{sample.scene_id}"
            inst = np.where(sample.valid, sample.instance, -1).astype(np.int32)
            if exact:
                arrays[key + "/xyz"] = np.asarray(sample.coord, np.float32)
                arrays[key + "/rgb"] = np.asarray(sample.color, np.uint8)
            else:
                lo = sample.coord.min(0)
                q = np.round((sample.coord - lo) / STEP)
                if q.max() >= 2 ** 16:
                    sys.exit(f"{spec}: scene {sample.scene_id} spans more than {2 ** 16 * STEP:.0f} m")
                # sorted along x and stored as x differences: compresses about twice as well
                q = q.astype(np.int64)
                order = np.lexsort((q[:, 2], q[:, 1], q[:, 0]))
                q, inst = q[order], inst[order]
                q[1:, 0] = np.diff(q[:, 0])
                arrays[key + "/q"] = np.ascontiguousarray(q.T.astype(np.uint16))  # (3, N): columns compress better
                arrays[key + "/lo"] = lo.astype(np.float64)
            if inst.max() >= 2 ** 15:
                sys.exit(f"{spec}: scene {sample.scene_id} has instance ids beyond int16")
            arrays[key + "/inst"] = inst.astype(np.int16)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    out.write_bytes(lzma.compress(buf.getvalue(), preset=6))
    n = len({k.split("/")[0] for k in arrays})
    print(f"{out}: {n} scenes, {out.stat().st_size / 1e6:.1f} MB")


def unpack(src: Path, out: Path) -> None:
    data = np.load(io.BytesIO(lzma.decompress(src.read_bytes())))
    out.mkdir(parents=True, exist_ok=True)
    keys = sorted({k.split("/")[0] for k in data.files})
    for key in keys:
        inst = data[key + "/inst"].astype(np.float32)
        if key + "/xyz" in data.files:
            xyz, rgb = data[key + "/xyz"], data[key + "/rgb"].astype(np.float32)
        else:
            q = data[key + "/q"].T.astype(np.int64)
            q[:, 0] = np.cumsum(q[:, 0])
            xyz = q.astype(np.float64) * STEP + data[key + "/lo"]
            rgb = np.zeros((len(inst), 3), np.float32)
        obj = inst >= 0
        sem = np.where(obj, 3.0, 1.0).astype(np.float32)
        a = np.concatenate([xyz.astype(np.float32), rgb, sem[:, None], np.where(obj, inst + 1, 0)[:, None]], 1)
        np.save(out / f"{key}.npy", a.astype(np.float32))
    print(f"{out}: {len(keys)} scenes")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("pack")
    p.add_argument("out", type=Path)
    p.add_argument("specs", nargs="+")
    p.add_argument("--exact", action="store_true", help="float32 coordinates and colours, no quantisation")
    u = sub.add_parser("unpack")
    u.add_argument("src", type=Path)
    u.add_argument("out", type=Path)
    a = ap.parse_args()
    if a.cmd == "pack":
        pack(a.out, a.specs, a.exact)
    else:
        unpack(a.src, a.out)


if __name__ == "__main__":
    main()
