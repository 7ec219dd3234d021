"""The dataset writer: Pointcept-layout scene folders, PLY export and the dataset manifest."""

from .manifest import MANIFEST_NAME, Manifest, read_manifest, scene_entry, versions
from .ply import instance_colors, instance_palette, ply_bytes, write_ply
from .writer import ARRAYS, META_NAME, load_scene_arrays, read_scene_meta, write_scene

__all__ = ["ARRAYS", "META_NAME", "MANIFEST_NAME", "Manifest", "read_manifest", "scene_entry", "versions", "instance_colors",
           "instance_palette", "ply_bytes", "write_ply", "load_scene_arrays", "read_scene_meta", "write_scene"]
