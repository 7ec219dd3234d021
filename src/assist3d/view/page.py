"""One self-contained HTML page that draws a :class:`~.sources.ViewData` in 3D with plotly.js.

The page inlines plotly.js (taken from the ``plotly`` Python package, the ``[view]`` extra) and the
points as base64 little-endian arrays, so it opens from disk with no network. Its own script
(``viewer.js`` beside this module) builds the colours, the hover text and the controls: colour by
RGB / instance / class / prediction, ground truth and prediction side by side with one camera,
point size. Text from input files reaches the page only as JSON data and is set as text, never as
markup.
"""

from __future__ import annotations

import base64
import html
import importlib.util
import json
import re
from pathlib import Path

import numpy as np

from ..core.errors import ConfigError
from ..core.fileio import write_bytes_atomic
from ..export.ply import BACKGROUND_RGB, instance_palette
from .sources import ViewData

__all__ = ["COLOR_MODES", "plotly_js", "page_html", "write_viewer"]

#: what the points can be coloured by (the ``--color`` of ``assist3d view``)
COLOR_MODES = ("rgb", "instance", "class", "prediction")
#: colours beyond this many labels repeat (label k takes colour k mod this)
MAX_PALETTE = 4096

_VIEWER_JS = Path(__file__).with_name("viewer.js")


def plotly_js() -> tuple[str, str]:
    """(plotly.js source, its version) from the installed ``plotly`` package, without importing it;
    a :class:`ConfigError` saying how to install it when it is absent."""
    spec = importlib.util.find_spec("plotly")
    if spec is None or not spec.submodule_search_locations:
        raise ConfigError("`assist3d view` needs plotly.js, which the plotly package ships: "
                          "pip install 'assist3d[view]'")
    for folder in spec.submodule_search_locations:
        path = Path(folder) / "package_data" / "plotly.min.js"
        if path.is_file():
            src = path.read_text(encoding="utf-8")
            m = re.search(r"plotly\.js v(\d+\.\d+\.\d+)", src[:500])
            return src, m.group(1) if m else "unknown"
    raise ConfigError("the installed plotly package has no package_data/plotly.min.js; "
                      "reinstall it: pip install --force-reinstall 'assist3d[view]'")


def _b64(a: np.ndarray, dtype: str) -> str:
    return base64.b64encode(np.ascontiguousarray(a, dtype=np.dtype(dtype)).tobytes()).decode("ascii")


def _hex(rgb) -> str:
    return "#%02x%02x%02x" % tuple(int(c) for c in rgb)


def _payload(data: ViewData, *, color: str, side_by_side: bool, point_size: float) -> dict:
    labels = [a for a in (data.instance, data.klass, data.pred) if a is not None and len(a)]
    top = max((int(a.max()) for a in labels), default=-1) + 1
    palette = instance_palette(min(max(top, 1), MAX_PALETTE))
    coord = np.asarray(data.coord, np.float32)
    scores = data.pred_scores
    return {
        "name": data.name,
        "notes": list(data.notes),
        "n": len(data),
        "x": _b64(coord[:, 0], "<f4"), "y": _b64(coord[:, 1], "<f4"), "z": _b64(coord[:, 2], "<f4"),
        "rgb": None if data.rgb is None else _b64(data.rgb.reshape(-1), "u1"),
        "instance": None if data.instance is None else _b64(data.instance, "<i4"),
        "klass": None if data.klass is None else _b64(data.klass, "<i4"),
        "pred": None if data.pred is None else _b64(data.pred, "<i4"),
        "predScores": None if scores is None else [round(float(s), 4) for s in scores],
        "classNames": list(data.class_names),
        "palette": [_hex(c) for c in palette],
        "background": _hex(BACKGROUND_RGB),
        "color": color,
        "sideBySide": side_by_side,
        "pointSize": point_size,
    }


def default_color(data: ViewData) -> str:
    """The colouring a page opens with: instances when the scene has ground truth, else the
    prediction, else the scan's colours."""
    if data.instance is not None:
        return "instance"
    if data.pred is not None:
        return "prediction"
    return "rgb"


def available_colors(data: ViewData) -> tuple[str, ...]:
    """The colour modes ``data`` can show."""
    have = {"rgb": data.rgb is not None, "instance": data.instance is not None,
            "class": data.klass is not None, "prediction": data.pred is not None}
    return tuple(m for m in COLOR_MODES if have[m])


def page_html(data: ViewData, *, color: str | None = None, side_by_side: bool = False,
              point_size: float = 2.0) -> str:
    """The viewer page of ``data`` as one HTML string (plotly.js inlined)."""
    color = color or default_color(data)
    if color not in COLOR_MODES:
        raise ConfigError(f"--color {color!r}: expected one of {', '.join(COLOR_MODES)}")
    if color not in available_colors(data):
        raise ConfigError(f"--color {color}: {data.name} has no {color} to colour by "
                          f"(it has: {', '.join(available_colors(data)) or 'only points'})")
    if side_by_side and (data.pred is None or data.instance is None):
        raise ConfigError("--side-by-side needs ground truth and a prediction (give a scene with labels and --pred)")
    if len(data) == 0:
        raise ConfigError(f"{data.name}: no points to show")
    lib, version = plotly_js()
    payload = json.dumps(_payload(data, color=color, side_by_side=side_by_side, point_size=point_size),
                         separators=(",", ":"), ensure_ascii=True)
    payload = payload.replace("</", "<\\/")  # never closes its script element
    viewer = _VIEWER_JS.read_text(encoding="utf-8")
    title = html.escape(f"assist3d view: {data.name}")
    return (
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
        f"<title>{title}</title>\n"
        "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
        "<meta name=\"generator\" content=\"assist3d view\">\n"
        f"<style>{_CSS}</style>\n"
        f"<!-- plotly.js {version} (MIT licence, Plotly, Inc.), inlined from the plotly Python package -->\n"
        f"<script>{lib}</script>\n</head>\n<body>\n{_BODY}\n"
        f"<script id=\"view-data\" type=\"application/json\">{payload}</script>\n"
        f"<script>{viewer}</script>\n</body>\n</html>\n"
    )


def write_viewer(path: str | Path, data: ViewData, **options) -> Path:
    """Write :func:`page_html` to ``path`` atomically; returns the path."""
    out = Path(path)
    write_bytes_atomic(out, page_html(data, **options).encode("utf-8"))
    return out


_CSS = """
html, body { margin: 0; height: 100%; font: 14px system-ui, sans-serif; color: #222; background: #fff; }
body { display: flex; flex-direction: column; }
#bar { display: flex; flex-wrap: wrap; align-items: center; gap: 6px 14px; padding: 6px 10px;
       border-bottom: 1px solid #ddd; background: #fafafa; }
#bar h1 { font-size: 15px; margin: 0 8px 0 0; }
#bar .group { display: flex; align-items: center; gap: 4px; }
#bar button { font: inherit; padding: 2px 9px; border: 1px solid #bbb; border-radius: 4px; background: #fff;
              cursor: pointer; }
#bar button[aria-pressed="true"] { background: #2b6cb0; border-color: #2b6cb0; color: #fff; }
#bar button:disabled { color: #aaa; cursor: not-allowed; }
#notes { padding: 2px 10px; font-size: 12px; color: #666; }
#titles { display: none; padding: 0 10px; font-size: 13px; color: #444; }
#titles.on { display: flex; }
#titles span { flex: 1; text-align: center; }
#plot { flex: 1; min-height: 300px; }
#tip { display: none; position: fixed; z-index: 10; pointer-events: none; padding: 4px 8px; font-size: 13px;
       background: #fff; border: 1px solid #888; border-radius: 4px; box-shadow: 0 1px 4px rgba(0,0,0,.2); }
"""

_BODY = """<div id="bar">
  <h1 id="name"></h1>
  <div class="group" role="group" aria-label="colour by">colour by
    <button type="button" data-color="rgb">RGB</button>
    <button type="button" data-color="instance">instance</button>
    <button type="button" data-color="class">class</button>
    <button type="button" data-color="prediction">prediction</button>
  </div>
  <label class="group"><input type="checkbox" id="side"> ground truth | prediction side by side</label>
  <label class="group">point size <input type="range" id="size" min="1" max="8" step="0.5"></label>
  <span id="status"></span>
</div>
<div id="notes"></div>
<div id="titles"><span>ground truth</span><span>prediction</span></div>
<div id="plot"></div>
<div id="tip" role="tooltip"></div>"""
