"""A top-down picture of a layout (PNG) for judging it at a glance.

The room polygon with its doors (brown) and windows (blue), every instance's footprint coloured by
group (floor blue, wall orange, on-top green, drawn over its support), its class name, and an
arrow pointing where its front faces.
"""

from __future__ import annotations

import io
import logging
from pathlib import Path

import numpy as np

from ..assets.catalog import Catalog
from ..core.contracts import SceneLayout, group_kind
from ..core.errors import shown
from ..core.fileio import write_bytes_atomic
from ..scene.room import opening_segment

log = logging.getLogger(__name__)

GROUP_STYLE = {  # face colour, edge colour, z-order
    "floor": ("#9ecae1", "#3182bd", 2),
    "wall": ("#fdae6b", "#e6550d", 3),
    "obj": ("#a1d99b", "#31a354", 4),
}
UNKNOWN_SIZE = (0.2, 0.2, 0.2)


def footprint_corners(pose: np.ndarray, size) -> np.ndarray:
    """(4, 2) float64: world x-y corners of an asset's footprint box (canonical size w x d) under
    ``pose`` ((4, 4) float64), counter-clockwise."""
    w, d = float(size[0]) / 2, float(size[1]) / 2
    local = np.array([[-w, -d], [w, -d], [w, d], [-w, d]])
    return local @ pose[:2, :2].T + pose[:2, 3]


def render_topdown(layout: SceneLayout, catalog: Catalog, path: str | Path, *, title: str | None = None) -> None:
    """Write a PNG of ``layout`` seen from above to ``path`` (atomically)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch, Polygon

    room = np.asarray(layout.room.polygon, dtype=np.float64)
    lo, hi = room.min(0), room.max(0)
    extent = np.maximum(hi - lo, 1.0)
    scale = 9.0 / float(extent.max())
    fig = Figure(figsize=(max(4.0, extent[0] * scale) + 0.5, max(4.0, extent[1] * scale) + 0.9), dpi=140)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    ax.add_patch(Polygon(room, closed=True, facecolor="#f4f4f4", edgecolor="black", linewidth=2.0, zorder=0))
    for op in layout.room.openings:
        seg = opening_segment(layout.room, op)
        color = "#8c510a" if op.kind == "door" else "#2b8cbe"
        ax.plot(seg[:, 0], seg[:, 1], color=color, linewidth=5 if op.kind == "door" else 4, solid_capstyle="butt",
                zorder=1)
    counts = {"floor": 0, "wall": 0, "obj": 0}
    parents = {i.parent for i in layout.instances if i.parent is not None}
    for inst in sorted(layout.instances, key=lambda i: (GROUP_STYLE[group_kind(i.group)][2], i.id)):
        kind = group_kind(inst.group)
        counts[kind] += 1
        face, edge, z = GROUP_STYLE[kind]
        if inst.asset in catalog:
            size = catalog.get(inst.asset).size
        else:
            size = UNKNOWN_SIZE
            log.warning("topdown: asset %s of instance %d is not in catalog %s; drawn as a 0.2 m square",
                        shown(inst.asset), inst.id, catalog.root)
        pose = np.asarray(inst.pose, dtype=np.float64)
        corners = footprint_corners(pose, size)
        ax.add_patch(Polygon(corners, closed=True, facecolor=face, edgecolor=edge, linewidth=0.8, alpha=0.85,
                             zorder=z))
        centre = pose[:2, 3]
        front = pose[:2, :2] @ np.array([0.0, -1.0])
        length = 0.5 * min(float(size[0]), float(size[1])) + 0.08
        ax.annotate("", xy=centre + front * length, xytext=centre, zorder=z + 0.1,
                    arrowprops={"arrowstyle": "->", "color": edge, "linewidth": 0.8})
        label_at = centre
        if inst.id in parents:  # keep the support's name clear of the objects drawn on it
            label_at = centre + pose[:2, :2] @ np.array([0.0, 0.5 * float(size[1]) - 0.06])
        ax.text(label_at[0], label_at[1], inst.class_name, fontsize=4.5, ha="center", va="center", zorder=z + 0.2,
                clip_on=True)
    margin = 0.3
    ax.set_xlim(lo[0] - margin, hi[0] + margin)
    ax.set_ylim(lo[1] - margin, hi[1] + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    handles = [Patch(facecolor=GROUP_STYLE[k][0], edgecolor=GROUP_STYLE[k][1], label=f"{k} ({counts[k]})")
               for k in ("floor", "wall", "obj")]
    handles += [Patch(color="#8c510a", label="door"), Patch(color="#2b8cbe", label="window")]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=6, frameon=False)
    head = title if title is not None else f"seed {layout.seed}"
    ax.set_title(f"{head}: {len(layout.instances)} placed, {len(layout.dropped)} dropped, "
                 f"room {layout.room.height:.2f} m high", fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    write_bytes_atomic(path, buf.getvalue())
