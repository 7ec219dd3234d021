"""``assist3d view``: one self-contained HTML page that shows a generated scene, a real scan or a
segmentation in 3D (plotly.js inlined; no network when the page is opened)."""

from .page import COLOR_MODES, available_colors, default_color, page_html, plotly_js, write_viewer
from .sources import SCANNET20_NAMES, ViewData, labels_from_masks, load_view, subsample

__all__ = ["COLOR_MODES", "SCANNET20_NAMES", "ViewData", "available_colors", "default_color", "labels_from_masks",
           "load_view", "page_html", "plotly_js", "subsample", "write_viewer"]
