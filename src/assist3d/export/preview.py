"""A one-page PNG of a generated scene: its layout from above and its point cloud from several
angles, coloured by instance (background grey), plus one view in the rendered colours.

Cut-away ("dollhouse") views drop the points whose normal faces away from the viewer, so the
near walls vanish and the furniture inside is visible. Everything comes from the scene folder
(``layout.json`` and the arrays); no catalog is needed.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import numpy as np

from ..core.contracts import SceneLayout, group_kind
from ..core import reading
from ..core.errors import DataError, shown
from ..core.fileio import write_bytes_atomic
from .ply import BACKGROUND_RGB, instance_colors
from .writer import load_scene_arrays

__all__ = ["render_preview", "find_scene_dir", "beside_dataset", "place_labels"]

MAX_POINTS = 120_000


def find_scene_dir(path: str | Path, scene: str | None = None) -> Path:
    """``path`` itself if it is a scene folder, else its scene ``scene`` or its first scene."""
    p = Path(path)
    if (p / "coord.npy").is_file():
        return p
    if not p.is_dir():
        raise DataError(f"{p}: not a scene folder or dataset folder")
    if scene is not None:
        if not (p / scene / "coord.npy").is_file():
            raise DataError(f"{p / scene}: no such scene (expected coord.npy inside)")
        return p / scene
    scenes = sorted(q for q in p.iterdir() if q.is_dir() and (q / "coord.npy").is_file())
    if not scenes:
        raise DataError(f"{p}: no scene folders with coord.npy found")
    return scenes[0]


def beside_dataset(path: str | Path, scene: str, suffix: str) -> Path:
    """A file for scene ``scene`` next to, never inside, the dataset that ``path`` names (a dataset
    folder, or a scene folder in one): ``<dataset>_<scene><suffix>`` beside the dataset folder; for a
    scene folder outside any dataset, ``<scene><suffix>`` beside it. Tools that read the dataset
    then never meet a stray file in it."""
    p = Path(path)
    if p.name in ("", ".", ".."):
        p = p.resolve()
    if (p / "coord.npy").is_file():
        if not (p.parent / "manifest.json").is_file():
            return p.parent / f"{scene}{suffix}"
        p = p.parent if p.parent.name not in ("", ".", "..") else p.parent.resolve()
    return p.parent / f"{p.name}_{scene}{suffix}"


def _view_basis(azim_deg: float, elev_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    a, e = math.radians(azim_deg), math.radians(elev_deg)
    to_eye = np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])
    right = np.array([-math.sin(a), math.cos(a), 0.0])
    up = np.cross(to_eye, right)
    return to_eye, right, up


def _draw_cloud(ax, coord, normal, rgb, azim: float, elev: float, title: str) -> None:
    to_eye, right, up = _view_basis(azim, elev)
    facing = normal @ to_eye > -0.05  # keep points whose surface faces the viewer
    c, col = coord[facing], rgb[facing]
    depth = c @ to_eye
    order = np.argsort(depth, kind="stable")  # far first, near drawn on top
    x, y = c[order] @ right, c[order] @ up
    ax.scatter(x, y, s=1.6, c=col[order] / 255.0, marker="o", linewidths=0, rasterized=True)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    ax.axis("off")


def _draw_layout(ax, layout: SceneLayout, coord, instance, palette_rgb) -> list[tuple[float, float, str, float]]:
    """Draw the room and the objects' footprints; returns the labels to place, (x, y, text, area)."""
    from matplotlib.patches import FancyArrow, Polygon

    room = np.asarray(layout.room.polygon, dtype=np.float64)
    ax.add_patch(Polygon(room, closed=True, facecolor="#f2f2f2", edgecolor="black", linewidth=1.8, zorder=0))
    for op in layout.room.openings:
        a, b = room[op.wall], room[(op.wall + 1) % len(room)]
        u = (b - a) / max(np.linalg.norm(b - a), 1e-9)
        s, e = a + u * (op.offset - op.width / 2), a + u * (op.offset + op.width / 2)
        ax.plot([s[0], e[0]], [s[1], e[1]], color="#8c510a" if op.kind == "door" else "#2b8cbe",
                linewidth=4, solid_capstyle="butt", zorder=1)
    order = np.argsort(instance, kind="stable")
    ids, starts = np.unique(instance[order], return_index=True)
    bounds = np.r_[starts, len(order)]
    by_id = {int(i): order[bounds[k]:bounds[k + 1]] for k, i in enumerate(ids) if i >= 0}
    labels: list[tuple[float, float, str, float]] = []
    for inst in sorted(layout.instances, key=lambda i: (i.pose[2, 3], i.id)):  # low objects first
        pts = by_id.get(inst.id)
        if pts is None or len(pts) < 3:
            continue
        pose = inst.pose
        local = (coord[pts, :2] - pose[:2, 3]) @ pose[:2, :2]  # into the object's yaw frame
        lo, hi = local.min(0), local.max(0)
        corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]]) @ pose[:2, :2].T + pose[:2, 3]
        col = palette_rgb[inst.id] / 255.0
        kind = group_kind(inst.group)
        ax.add_patch(Polygon(corners, closed=True, facecolor=(*col, 0.75), edgecolor="black",
                             linewidth=0.5 if kind == "obj" else 0.8, zorder=3 if kind == "obj" else 2))
        ctr = corners.mean(0)
        front = -pose[:2, 1]  # canonical front is -y
        ln = 0.35 * float(min(hi - lo))
        if kind != "obj" and ln > 0.05:
            ax.add_patch(FancyArrow(ctr[0], ctr[1], front[0] * ln, front[1] * ln, width=0.015, head_width=0.08,
                                    color="black", zorder=4, length_includes_head=True))
        if kind != "obj":
            labels.append((float(ctr[0]), float(ctr[1]), inst.class_name[:14], float(np.prod(hi - lo))))
    lo, hi = room.min(0), room.max(0)
    ax.set_xlim(lo[0] - 0.3, hi[0] + 0.3)
    ax.set_ylim(lo[1] - 0.3, hi[1] + 0.3)
    ax.set_aspect("equal")
    ax.set_title("layout (from points; arrows = fronts)", fontsize=9)
    ax.tick_params(labelsize=6)
    return labels


#: where a label may go, in points from its object's centre: on it first, then ever further around it
_LABEL_OFFSETS = ((0, 0), (0, 7), (0, -7), (12, 0), (-12, 0), (0, 14), (0, -14), (16, 8), (-16, 8), (16, -8),
                  (-16, -8), (0, 21), (0, -21), (24, 0), (-24, 0))


def place_labels(ax, labels, renderer, *, fontsize: float = 6.0) -> tuple[list, int]:
    """Write ``labels`` ((x, y, text, priority) in data coordinates) on ``ax`` so that no two overlap
    and none leaves the axes: the highest priority first, each at its point or the first free spot of
    :data:`_LABEL_OFFSETS` around it; a label with no free spot is left out. Call it once the figure's
    layout is final. Returns (the Text artists written, how many labels were left out)."""
    from matplotlib.transforms import ScaledTranslation

    fig = ax.figure
    frame = ax.get_window_extent(renderer)
    taken: list = []
    written: list = []
    left_out = 0
    for x, y, text, _ in sorted(labels, key=lambda lab: (-lab[3], lab[2])):
        t = ax.text(x, y, text, fontsize=fontsize, ha="center", va="center", zorder=5,
                    bbox={"boxstyle": "square,pad=0.1", "facecolor": "white", "edgecolor": "none", "alpha": 0.75})
        for dx, dy in _LABEL_OFFSETS:
            t.set_transform(ax.transData + ScaledTranslation(dx / 72, dy / 72, fig.dpi_scale_trans))
            box = t.get_window_extent(renderer).expanded(1.06, 1.25)  # the white box around the text
            inside = (box.x0 >= frame.x0 and box.x1 <= frame.x1 and box.y0 >= frame.y0 and box.y1 <= frame.y1)
            if inside and not any(box.overlaps(b) for b in taken):
                taken.append(box)
                written.append(t)
                break
        else:
            t.remove()
            left_out += 1
    return written, left_out


def render_preview(scene_dir: str | Path, out_png: str | Path, *, seed: int = 0) -> Path:
    """Write the preview PNG of one scene folder (atomically); returns its path."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    d = Path(scene_dir)
    arrays = load_scene_arrays(d)
    try:
        layout = SceneLayout.from_json(reading.read_json(d / "layout.json", what="layout"))
    except DataError as e:
        raise DataError(f"{shown(d / 'layout.json', 400)}: unreadable layout ({reading.problem(e, d / 'layout.json')})") from None
    except (ValueError, KeyError, TypeError, AttributeError, IndexError) as e:
        raise DataError(f"{d / 'layout.json'}: unreadable layout ({e})") from None
    coord, normal = arrays["coord"].astype(np.float64), arrays["normal"].astype(np.float64)
    instance, color = arrays["instance"], arrays["color"]
    n = len(coord)
    idx = np.arange(n)
    if n > MAX_POINTS:
        idx = np.sort(np.random.default_rng(seed).choice(n, MAX_POINTS, replace=False))
    top = max(int(instance.max(initial=-1)), max((i.id for i in layout.instances), default=-1)) + 1
    palette = instance_colors(np.arange(top)) if top else np.zeros((0, 3), np.uint8)
    inst_rgb = np.zeros((n, 3), np.uint8)
    inst_rgb[:] = BACKGROUND_RGB
    obj = instance >= 0
    inst_rgb[obj] = palette[instance[obj]]

    fig = Figure(figsize=(15, 9.6), dpi=110)
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 3)
    labels = _draw_layout(axes[0, 0], layout, coord, instance, palette)
    s = idx
    _draw_cloud(axes[0, 1], coord[s], normal[s], color[s], 35, 50, "rendered colour, cut-away view")
    _draw_cloud(axes[0, 2], coord[s], normal[s], inst_rgb[s], 35, 50, "instances, cut-away view")
    _draw_cloud(axes[1, 0], coord[s], normal[s], inst_rgb[s], 155, 40, "instances, azimuth 155")
    _draw_cloud(axes[1, 1], coord[s], normal[s], inst_rgb[s], 275, 40, "instances, azimuth 275")
    _draw_cloud(axes[1, 2], coord[s], normal[s], inst_rgb[s], -90, 90, "instances, from above")
    n_inst = len(set(instance[obj].tolist()))
    fig.suptitle(f"{d.name}: {len(layout.instances)} objects placed, {n_inst} with points, {n:,} points "
                 f"(grey = background)", fontsize=12)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    renderer = fig.canvas.get_renderer()
    axes[0, 0].apply_aspect()
    _, left_out = place_labels(axes[0, 0], labels, renderer)
    if left_out:
        axes[0, 0].set_title(f"layout (from points; arrows = fronts)\n{left_out} of {len(labels)} labels left out "
                             "where they would overlap", fontsize=9)
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    out = Path(out_png)
    write_bytes_atomic(out, buf.getvalue())
    return out
