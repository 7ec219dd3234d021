"""Binary glTF of a layout: one mesh node per instance and per room surface, for viewers and
other tools (``output.save_mesh``, ``assist3d layout``)."""

from __future__ import annotations

import io
import logging
from pathlib import Path

import numpy as np

from ..assets.catalog import Catalog
from ..core.contracts import MeshData, SceneLayout
from ..core.fileio import write_bytes_atomic
from ..scene.assemble import labelled_meshes
from ..scene.shell import build_shell

log = logging.getLogger(__name__)

__all__ = ["export_glb"]


def _colored(mesh: MeshData):
    """A trimesh whose vertex colours reproduce the per-face colours exactly: a vertex is
    duplicated only where faces of different colours meet, so most vertices stay shared."""
    import trimesh

    f = mesh.faces.astype(np.int64)
    code = (mesh.face_colors.astype(np.int64) @ np.array([65536, 256, 1], dtype=np.int64))
    key = f * (1 << 24) + code[:, None]
    uniq, inverse = np.unique(key.ravel(), return_inverse=True)
    verts = mesh.vertices[uniq >> 24]
    rgb = np.stack([(uniq >> 16) & 255, (uniq >> 8) & 255, uniq & 255], 1).astype(np.uint8)
    rgba = np.concatenate([rgb, np.full((len(uniq), 1), 255, np.uint8)], 1)
    return trimesh.Trimesh(vertices=verts, faces=inverse.reshape(-1, 3), vertex_colors=rgba, process=False)


def export_glb(layout: SceneLayout, catalog: Catalog, path: str | Path) -> None:
    """Write the scene as binary glTF: one mesh node per instance (filled openings included) named
    ``instance_<id>`` and one per room surface named ``background_<name>`` (floor, wall_0, ...,
    ceiling), vertices in the world frame of the poses (node transforms are identity), per-face
    colours as vertex colours (a vertex is duplicated where faces of different colours meet).
    Written atomically."""
    import trimesh

    scene = trimesh.Scene()
    for ident, _, mesh in labelled_meshes(layout, catalog):
        name = f"instance_{ident}"
        scene.add_geometry(_colored(mesh), node_name=name, geom_name=name)
    for name, mesh in build_shell(layout.room):
        if len(mesh.faces):
            node = f"background_{name}"
            scene.add_geometry(_colored(mesh), node_name=node, geom_name=node)
    buf = io.BytesIO()
    scene.export(buf, file_type="glb")
    write_bytes_atomic(path, buf.getvalue())
    log.debug("wrote %s (%d nodes)", path, len(scene.graph.nodes_geometry))
