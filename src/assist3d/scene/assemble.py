"""Scene assembly: every instance mesh moved by its pose, plus the room shell, as one labelled
triangle soup (:class:`~assist3d.core.contracts.SceneMesh`); the GLB file is written by
:func:`assist3d.export.glb.export_glb`."""

from __future__ import annotations

import logging
from typing import Sequence

import numpy as np

from ..assets.catalog import Catalog
from ..core.contracts import MeshData, SceneLayout, SceneMesh
from ..core.errors import AssetError
from ..core.geometry import transform_points
from .shell import build_shell, opening_meshes

log = logging.getLogger(__name__)

__all__ = ["assemble_scene", "instance_meshes", "labelled_meshes"]


def instance_meshes(layout: SceneLayout, catalog: Catalog) -> list[tuple[int, MeshData]]:
    """(instance id, mesh in world coordinates) for every instance of ``layout``, in order."""
    out = []
    for inst in layout.instances:
        try:
            mesh = catalog.load_mesh(inst.asset)
        except AssetError as e:
            raise AssetError(f"instance {inst.id}: {e}") from None
        verts = transform_points(inst.pose, mesh.vertices.astype(np.float64)).astype(np.float32)
        out.append((inst.id, MeshData(verts, mesh.faces.copy(), mesh.face_colors.copy())))
    return out


def labelled_meshes(layout: SceneLayout, catalog: Catalog) -> list[tuple[int, str, MeshData]]:
    """(instance id, class, world mesh) of every labelled object: the layout's instances, then the
    objects filling the room's openings (``room.fill_openings``; classes ``door`` and ``window``)."""
    by_id = {i.id: i for i in layout.instances}
    out = [(ident, by_id[ident].class_name, mesh) for ident, mesh in instance_meshes(layout, catalog)]
    return out + opening_meshes(layout.room)


def assemble_scene(layout: SceneLayout, catalog: Catalog, classes: Sequence[str]) -> SceneMesh:
    """The whole scene as one mesh: instances and filled openings (face_instance = instance id,
    face_segment = ``classes.index(class)`` or -1 for a class not in the list, face_part = instance
    id) followed by the room shell (face_instance = face_segment = -1, face_part = -(k + 1) for background part
    k named ``background_names[k]``)."""
    class_index = {c: i for i, c in enumerate(classes)}
    verts, faces, colors, inst_ids, segs, parts = [], [], [], [], [], []
    offset = 0
    for ident, class_name, mesh in labelled_meshes(layout, catalog):
        nf = len(mesh.faces)
        verts.append(mesh.vertices)
        faces.append(mesh.faces + offset)
        colors.append(mesh.face_colors)
        inst_ids.append(np.full(nf, ident, np.int32))
        segs.append(np.full(nf, class_index.get(class_name, -1), np.int32))
        parts.append(np.full(nf, ident, np.int32))
        offset += len(mesh.vertices)
    names = []
    for k, (name, mesh) in enumerate(build_shell(layout.room)):
        nf = len(mesh.faces)
        names.append(name)
        verts.append(mesh.vertices)
        faces.append(mesh.faces + offset)
        colors.append(mesh.face_colors)
        inst_ids.append(np.full(nf, -1, np.int32))
        segs.append(np.full(nf, -1, np.int32))
        parts.append(np.full(nf, -(k + 1), np.int32))
        offset += len(mesh.vertices)
    return SceneMesh(
        vertices=np.concatenate(verts).astype(np.float32),
        faces=np.concatenate(faces).astype(np.int32),
        face_colors=np.concatenate(colors).astype(np.uint8),
        face_instance=np.concatenate(inst_ids),
        face_segment=np.concatenate(segs),
        face_part=np.concatenate(parts),
        background_names=tuple(names),
    )
