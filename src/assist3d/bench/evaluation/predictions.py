"""Prediction files: our compact ``.npz`` and the ScanNet benchmark's text format.

``<scene_id>.npz`` holds ``masks`` (bool, (M, N)) and ``scores`` (float32, (M,)), written with
``numpy.savez_compressed`` so plain ``numpy.load`` reads both keys. N and the point order are those
of the dataset reader's scene.

The benchmark text format is one ``<scene_id>.txt`` per scene with lines
``pred_mask/<scene_id>_<k>.txt <label_id> <score>`` and, per mask, a file holding one ``0``/``1``
per point (paths relative to the ``.txt``; a path that is absolute or resolves outside the
``.txt``'s folder is refused before it is read). Class-agnostic evaluation treats every mask as an
object whatever its label id.
"""

from __future__ import annotations

import io
import logging
from pathlib import Path

import numpy as np

from ...core import reading
from ...core.errors import DataError, shown
from ...core.fileio import write_bytes_atomic, write_text_atomic
from ...core.paths import inside, safe_name

log = logging.getLogger(__name__)

#: The label id written with every mask in the benchmark text format: 39, "otherfurniture", an object
#: class of the ScanNet benchmark (its instance evaluation scores the nyu40 ids 3-12, 14, 16, 24, 28, 33,
#: 34, 36 and 39 and drops every other, so a label such as 1, "wall", makes the official script discard
#: every prediction). To score class-agnostically with the official script, give every ground-truth
#: object the same class (``assist3d evaluate`` does this itself).
DEFAULT_LABEL_ID = 39
#: The nyu40 ids the ScanNet benchmark's instance evaluation scores.
SCANNET_INSTANCE_IDS = frozenset({3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 14, 16, 24, 28, 33, 34, 36, 39})


def _validated(path: Path, masks: np.ndarray, scores: np.ndarray, n_points: int | None) -> tuple[np.ndarray, np.ndarray]:
    masks = np.asarray(masks)
    scores = np.asarray(scores)
    if masks.ndim != 2:
        raise DataError(f"{path}: masks must have shape (M, N), got {masks.shape}")
    if scores.ndim != 1 or len(scores) != len(masks):
        raise DataError(f"{path}: {scores.shape} scores for {len(masks)} masks")
    if n_points is not None and masks.shape[1] != n_points:
        raise DataError(f"{path}: masks have {masks.shape[1]} points, the scene has {n_points}")
    if not np.all(np.isfinite(scores)):
        raise DataError(f"{path}: scores must be finite numbers")
    return masks.astype(bool, copy=False), scores.astype(np.float32, copy=False)


def save_predictions(path: str | Path, masks: np.ndarray, scores: np.ndarray) -> Path:
    """Write ``masks`` (M, N) bool and ``scores`` (M,) float32 to a compressed ``.npz`` atomically."""
    path = Path(path)
    masks, scores = _validated(path, masks, scores, None)
    buf = io.BytesIO()
    np.savez_compressed(buf, masks=np.ascontiguousarray(masks), scores=np.ascontiguousarray(scores))
    write_bytes_atomic(path, buf.getvalue())
    return path


def load_predictions(path: str | Path, n_points: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Read ``(masks (M, N) bool, scores (M,) float32)``; checks N against ``n_points`` if given."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"{path}: prediction file not found")
    try:
        z = reading.read_npz(path, keys=("masks", "scores"), what="prediction npz")
    except DataError as e:
        raise DataError(f"{shown(path, 400)}: cannot read prediction npz ({reading.problem(e, path)})") from None
    masks, scores = z["masks"], z["scores"]
    if masks.ndim == 1 and masks.size == 0:
        masks = masks.reshape(0, n_points or 0)
    return _validated(path, masks, scores, n_points)


def _mask_bytes(mask: np.ndarray) -> bytes:
    out = np.full(2 * len(mask), ord("\n"), np.uint8)
    out[0::2] = mask.astype(np.uint8) + ord("0")
    return out.tobytes()


def export_scannet_txt(out_dir: str | Path, scene_id: str, masks: np.ndarray, scores: np.ndarray, *,
                       label_id: int = DEFAULT_LABEL_ID) -> Path:
    """Write one scene in the benchmark text format under ``out_dir``, every mask with ``label_id``
    (:data:`DEFAULT_LABEL_ID`); returns the ``.txt`` path."""
    out_dir = Path(out_dir)
    safe_name(scene_id, what=f"{out_dir}: scene id")
    txt = out_dir / f"{scene_id}.txt"
    masks, scores = _validated(txt, masks, scores, None)
    lines = []
    for k in range(len(masks)):
        rel = f"pred_mask/{scene_id}_{k:03d}.txt"
        write_bytes_atomic(out_dir / rel, _mask_bytes(masks[k]))
        lines.append(f"{rel} {int(label_id)} {float(scores[k]):.6f}")
    write_text_atomic(txt, "\n".join(lines) + ("\n" if lines else ""))
    return txt


def _read_mask_file(path: Path, n_points: int | None) -> np.ndarray:
    raw = reading.read_bytes(path, limit=reading.MAX_TEXT_BYTES, what="mask file")
    arr = np.frombuffer(raw, np.uint8)
    if len(arr) % 2 == 0 and np.all(arr[1::2] == ord("\n")) and np.all((arr[0::2] == ord("0")) | (arr[0::2] == ord("1"))):
        mask = arr[0::2] == ord("1")
    else:
        try:
            mask = np.array(raw.split(), dtype=np.float64) != 0
        except ValueError:
            raise DataError(f"{path}: mask file must hold one number per line") from None
    if n_points is not None and len(mask) != n_points:
        raise DataError(f"{path}: mask has {len(mask)} lines, the scene has {n_points} points")
    return mask


def import_scannet_txt(path: str | Path, n_points: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Read one scene's benchmark ``.txt`` and its mask files into ``(masks, scores)``."""
    path = Path(path)
    lines = reading.read_text(path, what="benchmark prediction list").splitlines()
    masks: list[np.ndarray] = []
    scores: list[float] = []
    for line_no, line in enumerate(lines, start=1):
        tok = line.split()
        if not tok:
            continue
        if len(tok) != 3:
            raise DataError(f"{path}: line {line_no}: expected '<mask file> <label id> <score>', got '{shown(line)}'")
        try:
            int(tok[1])
            scores.append(float(tok[2]))
        except ValueError:
            raise DataError(f"{path}: line {line_no}: label id or score is not a number: '{shown(line)}'") from None
        mask_path = inside(path.parent, tok[0], what=f"{path}: line {line_no}")
        mask = _read_mask_file(mask_path, n_points)
        if masks and len(mask) != len(masks[0]):
            raise DataError(f"{mask_path}: {len(mask)} lines, earlier masks have {len(masks[0])}")
        masks.append(mask)
    if not masks:
        return np.zeros((0, n_points or 0), bool), np.zeros(0, np.float32)
    return np.stack(masks), np.asarray(scores, np.float32)


def convert_predictions(src: str | Path, dst: str | Path, *, to: str, label_id: int = DEFAULT_LABEL_ID) -> int:
    """Convert a folder of predictions between ``npz`` and the benchmark ``txt`` format.

    ``to="txt"`` reads every ``*.npz`` in ``src`` and writes each mask with ``label_id``; ``to="npz"``
    every ``*.txt`` (label ids are not kept: every mask is an object). Returns the scene count.
    """
    src, dst = Path(src), Path(dst)
    if to not in ("txt", "npz"):
        raise DataError(f"convert_predictions: to={to!r}; expected 'txt' or 'npz'")
    files = sorted(src.glob("*.npz" if to == "txt" else "*.txt"))
    for f in files:
        if to == "txt":
            masks, scores = load_predictions(f)
            export_scannet_txt(dst, f.stem, masks, scores, label_id=label_id)
        else:
            masks, scores = import_scannet_txt(f)
            save_predictions(dst / f"{f.stem}.npz", masks, scores)
    return len(files)
