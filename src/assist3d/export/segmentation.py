"""Pictures of a segmentation: a distinct colour per instance and a top view PNG."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..core.fileio import write_bytes_atomic


def instance_colors(labels: np.ndarray) -> np.ndarray:
    """(N, 3) uint8: a distinct colour per instance (``labels`` >= 0), grey for points in none."""
    rng = np.random.default_rng(7)
    k = int(labels.max()) + 1 if len(labels) and labels.max() >= 0 else 0
    pal = (rng.uniform(0.15, 1.0, (max(k, 1), 3)) * 255).astype(np.uint8)
    out = np.full((len(labels), 3), 150, np.uint8)
    sel = labels >= 0
    out[sel] = pal[labels[sel]]
    return out


def write_top_view(path: str | Path, coord: np.ndarray, colors: np.ndarray, title: str) -> None:
    """A PNG top view (along z) of ``coord`` (N, 3) metres coloured by ``colors`` (N, 3) uint8, written atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    order = np.argsort(coord[:, 2])
    fig, ax = plt.subplots(figsize=(7, 7), dpi=110)
    ax.scatter(coord[order, 0], coord[order, 1], c=colors[order] / 255.0, s=1.0, linewidths=0)
    ax.set_aspect("equal")
    ax.set_title(title)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", bbox_inches="tight")
    plt.close(fig)
    write_bytes_atomic(Path(path), buf.getvalue())
