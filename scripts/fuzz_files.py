#!/usr/bin/env python
"""A seeded mutation fuzzer over the files users hand to assist3d: every outcome classified.

Usage::

    PYTHONPATH=src python scripts/fuzz_files.py [--cases 1000] [--seed 0] [--only KIND] [--case I]
                                                [--cli N] [--json out.json] [--markdown]

It builds valid examples of every input kind first (a 2-scene dataset generated from the built-in
procedural library and that library's catalog, a generation / training / segmenter config, a
mesh-import folder with one mesh of each supported format and CSV / JSON manifests, a real scan
cut to 3,000 points as ``.npy`` and ``.ply``, predictions as ``.npz`` and in the benchmark text
format, the shipped segmenter checkpoint), then runs ``--cases`` cases. Case ``i`` takes target
``i mod T`` and that target's operator ``(i div T) mod O`` -- truncate, flip bytes, swap the
encoding (or the byte order), inflate counts, nest structures -- with parameters drawn from a
generator seeded by ``(seed, i)``: the same seed gives the same cases, and ``--case I`` reruns one.
Three more cases always follow (:data:`FAMILIES`): the damage issue 54 started from, a config in
Latin-1, a config nested 5,000 levels and a dataset ``manifest.json`` nested 100,000 levels.

Each case copies the example's folder, mutates one file and calls what the command that reads it
calls (``generate``'s config reader, ``assets stats``'s catalog, ``assets import meshes``,
``segment``'s scan reader, ``evaluate``'s prediction readers, ``metrics``' dataset reading,
``segment --checkpoint``'s loader) in a forked child with a time limit and a memory cap. With
``--cli N`` the first N cases also run the command line itself in a subprocess (its top-level error
handling). Outcomes:

``clear``      the project's own error naming the file (or its folder), or a result, with a warning
               naming the file where the damage is certain (or harmless damage accepted)
``traceback``  any other exception, or the child died (a signal, the memory cap)
``silent``     a result, no warning, for damage that must be refused (a count past the file's end,
               bytes that are not UTF-8, nesting past the bound, a cut binary file)
``unclear``    the project's error, but naming neither the file nor its folder
``hang``       the time limit ran out
``loss``       a file of the case's folder other than the command's outputs changed or vanished

It prints a table (kind x outcome, and operator x outcome) and exits 1 if any outcome is not clear.
"""

from __future__ import annotations

import argparse
import hashlib
import io
import json
import logging
import os
import random
import resource
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from assist3d.learn.segmenter.shipped import SHIPPED_NAME

ROOT = Path(__file__).resolve().parents[1]
CLASSES = ("clear", "traceback", "silent", "unclear", "hang", "loss")
OPERATORS = ("truncate", "flip", "encoding", "inflate", "nest")

TINY_GEN = {
    "seed": 11,
    "assets": {"procedural_count": 60},
    "selection": {"floor_count": 6, "wall_count": 2, "on_top_count": 1},
    "room": {"area_min": 10.0, "area_max": 16.0},
    "layout": {"group_budget_s": 120.0},
    "render": {"width": 80, "height": 60, "fx": 72.2, "fy": 72.2, "vantage_points": 2, "views_per_point": 6},
}
SCAN_POINTS = 3000
REAL_SCAN = ROOT.parent / "shared" / "data" / "real" / "scannet_scene0451_01.npy"
CHECKPOINT = ROOT / "src" / "assist3d" / "resources" / "models" / SHIPPED_NAME


# ------------------------------------------------------------------------------------------------
# the valid examples


def build_examples(root: Path) -> None:
    """Write every example under ``root`` (run in a subprocess: the fuzzer's own process stays free
    of thread pools, so its forked children never inherit a held lock)."""
    import numpy as np
    import yaml

    os.environ["ASSIST3D_CACHE"] = str(root / "cache")
    from assist3d.assets import open_catalog
    from assist3d.bench.evaluation.predictions import export_scannet_txt, save_predictions
    from assist3d.config import parse_config
    from assist3d.export.ply import ply_bytes
    from assist3d.pipeline import generate_dataset

    # configs: the files users write
    cfg = root / "config"
    cfg.mkdir(parents=True)
    (cfg / "generate.yaml").write_text(yaml.safe_dump(TINY_GEN, sort_keys=False))
    shutil.copy(ROOT / "configs" / "small-cpu.yaml", cfg / "train.yaml")
    shutil.copy(ROOT / "configs" / "segmenter.yaml", cfg / "segmenter.yaml")
    # a dataset folder and the catalog it was made from
    generate_dataset(parse_config(TINY_GEN), root / "dataset", range(2))
    catalog = open_catalog(None, procedural_count=60)
    shutil.copytree(catalog.root, root / "catalog")
    # meshes of each supported format, and the manifests that list them
    import trimesh

    rec = catalog.records[0]
    m = catalog.load_mesh(rec)
    tm = trimesh.Trimesh(m.vertices, m.faces, face_colors=m.face_colors, process=False)
    meshes = root / "meshes"
    meshes.mkdir()
    rows = []
    for ext in ("obj", "glb", "ply", "stl", "off"):
        kw = {"encoding": "binary"} if ext == "ply" else {}
        blob = tm.export(file_type=ext, **kw)
        (meshes / f"chair.{ext}").write_bytes(blob.encode() if isinstance(blob, str) else blob)
        rows.append({"path": f"chair.{ext}", "class": "chair", "up": "+z", "front": "+y"})
    for name, blob in tm.export(file_type="gltf").items():  # the JSON and its buffer file beside it
        (meshes / ("chair.gltf" if name.endswith(".gltf") else name)).write_bytes(blob)
    rows.append({"path": "chair.gltf", "class": "chair", "up": "+z", "front": "+y"})
    blob = tm.export(file_type="ply", encoding="ascii")
    (meshes / "chair-ascii.ply").write_bytes(blob.encode() if isinstance(blob, str) else blob)
    rows.append({"path": "chair-ascii.ply", "class": "chair", "up": "+z", "front": "+y"})
    (meshes / "manifest.json").write_text(json.dumps(rows, indent=1))
    (meshes / "manifest.csv").write_text("path,class,up,front\n" + "".join(
        f"{r['path']},{r['class']},{r['up']},{r['front']}\n" for r in rows))
    # a real scan, cut to SCAN_POINTS points, as .npy and .ply
    scans = root / "scan"
    scans.mkdir()
    if REAL_SCAN.is_file():
        a = np.load(REAL_SCAN)[:SCAN_POINTS]
    else:  # pragma: no cover - a checkout without the shared data: the dataset's first scene
        d = root / "dataset" / "scene_000000"
        n = min(SCAN_POINTS, len(np.load(d / "coord.npy")))
        a = np.concatenate([np.load(d / "coord.npy")[:n], np.load(d / "color.npy")[:n].astype(np.float32),
                            np.load(d / "segment.npy")[:n, None].astype(np.float32),
                            np.load(d / "instance.npy")[:n, None].astype(np.float32)], axis=1)
    np.save(scans / "scan.npy", np.ascontiguousarray(a, np.float32))
    from assist3d.core.contracts import PointSample

    n = len(a)
    sample = PointSample(scene_id="scan", coord=a[:, :3].astype(np.float32), color=a[:, 3:6].astype(np.uint8),
                         normal=np.zeros((n, 3), np.float32), instance=np.full(n, -1, np.int32),
                         segment=np.full(n, -1, np.int32), valid=np.ones(n, bool))
    (scans / "scan.ply").write_bytes(ply_bytes(sample))
    # the same scan as a ScanNet scene folder (mesh, over-segmentation, aggregation, label table)
    from assist3d.data.ply import write_ply

    sn = root / "scannet" / "scans" / "scene0000_00"
    sn.mkdir(parents=True)
    faces = np.stack([np.arange(0, n - 2, 3), np.arange(1, n - 1, 3), np.arange(2, n, 3)], axis=1)
    write_ply(sn / "scene0000_00_vh_clean_2.ply", a[:, :3], np.clip(a[:, 3:6], 0, 255).astype(np.uint8), faces)
    segs = a[:, 7].astype(int).tolist()
    (sn / "scene0000_00_vh_clean_2.0.010000.segs.json").write_text(json.dumps({"sceneId": "scene0000_00",
                                                                                "segIndices": segs}))
    labels = ("wall", "chair", "table")
    groups = [{"id": k, "objectId": k, "segments": [s_], "label": labels[k % 3]}
              for k, s_ in enumerate(sorted(set(segs)))]
    (sn / "scene0000_00.aggregation.json").write_text(json.dumps({"sceneId": "scannet.scene0000_00",
                                                                  "segGroups": groups}, indent=1))
    (root / "scannet" / "scannetv2-labels.combined.tsv").write_text(
        "id\traw_category\tcategory\tcount\tnyu40id\n1\twall\twall\t10\t1\n2\tchair\tchair\t10\t5\n"
        "3\ttable\ttable\t10\t7\n")
    # predictions for the dataset's first scene, in both formats
    n0 = len(np.load(root / "dataset" / "scene_000000" / "coord.npy"))
    inst = np.load(root / "dataset" / "scene_000000" / "instance.npy")
    ids = [i for i in np.unique(inst) if i >= 0][:4]
    masks = np.stack([inst == i for i in ids]) if ids else np.zeros((0, n0), bool)
    scores = np.linspace(0.9, 0.5, len(masks)).astype(np.float32)
    preds = root / "predictions"
    save_predictions(preds / "scene_000000.npz", masks, scores)
    export_scannet_txt(preds / "txt", "scene_000000", masks, scores)
    # the shipped checkpoint
    ckpt = root / "checkpoint"
    ckpt.mkdir()
    shutil.copy(CHECKPOINT, ckpt / "model.pt")


# ------------------------------------------------------------------------------------------------
# targets: a file of an example and the reading a command does


@dataclass(frozen=True)
class Target:
    kind: str  # the table's row: config, catalog, mesh manifest, mesh, scan, scannet scene, predictions, ...)
    name: str  # e.g. "mesh:chair.glb"
    folder: str  # the example folder copied for each case
    file: str  # the file mutated, relative to the folder
    fmt: str  # yaml | json | csv | text | npy | npz | ply | obj | glb | stl | off | pt
    read: Callable[[Path], object]  # reads the copied folder as the command does; returns what it got
    outputs: tuple[str, ...] = ()  # files the command writes (not a loss when they change)
    cli: Callable[[Path], list[str]] | None = None  # the command line, for --cli


def _read_generate_config(d: Path):
    from assist3d.config.presets import compose

    return compose(d / "generate.yaml", None, {})


def _read_train_config(d: Path):
    from assist3d.learn.engine.config import load_train_config

    return load_train_config(d / "train.yaml")


def _read_segmenter_config(d: Path):
    from assist3d.cli.segment import _segmenter_config
    from assist3d.learn.segmenter.config import parse_segmenter_config

    return parse_segmenter_config(_segmenter_config(d / "segmenter.yaml"), str(d / "segmenter.yaml"))


def _read_catalog(d: Path):
    from assist3d.assets.catalog import Catalog

    cat = Catalog.open(d)
    return [cat.load_mesh(r).faces.shape for r in cat.records]


def _import(manifest: str) -> Callable[[Path], object]:
    def read(d: Path):
        from assist3d.assets.catalog import Catalog
        from assist3d.assets.meshes import import_meshes

        report = import_meshes(Catalog(d / "_catalog"), d, d / manifest, workers=1)
        for s in report.skipped:  # what `assets import meshes` prints, one line per skipped file
            logging.getLogger("assist3d.fuzz").warning("skipped %s: %s", s.path, s.reason)
        return report.added
    return read


def _read_scan(name: str) -> Callable[[Path], object]:
    def read(d: Path):
        from assist3d.data.scanfile import read_scan

        return read_scan(d / name)
    return read


def _read_dataset(d: Path):
    from assist3d.data import open_dataset
    from assist3d.bench.metrics.report import _load_layout
    from assist3d.export.manifest import read_manifest
    from assist3d.export.writer import read_scene_meta

    read_manifest(d, fix="")
    ds = open_dataset(f"assist3d:{d}")
    out = [len(s) for s in ds]
    for sid in sorted(p.name for p in d.glob("scene_*")):
        _load_layout(d / sid)
        if read_scene_meta(d / sid) is None:  # generate's resume redoes such a scene
            logging.getLogger("assist3d.fuzz").warning("%s: incomplete scene (its marker does not match)", d / sid)
    return out


def _read_scannet(d: Path):
    from assist3d.data import open_dataset

    return [len(s) for s in open_dataset(f"scannet:{d}")]


def _read_npz_predictions(d: Path):
    from assist3d.bench.evaluation.predictions import load_predictions

    return load_predictions(d / "scene_000000.npz", n_points=None)


def _read_txt_predictions(d: Path):
    from assist3d.bench.evaluation.predictions import import_scannet_txt

    return import_scannet_txt(d / "txt" / "scene_000000.txt", n_points=None)


def _read_checkpoint(d: Path):
    from assist3d.learn.segmenter.checkpoint import load_segmenter

    return load_segmenter(d / "model.pt").config


def _cli_generate(d: Path) -> list[str]:
    return ["generate", "--config", str(d / "generate.yaml"), "--out", str(d / "_out"), "--only", "0"]


def targets(examples: Path) -> list[Target]:
    ds = examples / "dataset"
    scene = "scene_000000"
    out = [
        Target("config", "config:generate.yaml", "config", "generate.yaml", "yaml", _read_generate_config,
               cli=_cli_generate),
        Target("config", "config:train.yaml", "config", "train.yaml", "yaml", _read_train_config),
        Target("config", "config:segmenter.yaml", "config", "segmenter.yaml", "yaml", _read_segmenter_config),
        Target("catalog", "catalog:index.json", "catalog", "index.json", "json", _read_catalog,
               cli=lambda d: ["assets", "stats", "--library", str(d)]),
    ]
    mesh_npz = sorted(p.name for p in (examples / "catalog" / "meshes").glob("*.npz"))[0]
    out.append(Target("catalog", "catalog:mesh.npz", "catalog", f"meshes/{mesh_npz}", "npz", _read_catalog))
    for manifest, fmt in (("manifest.json", "json"), ("manifest.csv", "csv")):
        out.append(Target("mesh manifest", f"manifest:{manifest}", "meshes", manifest, fmt, _import(manifest),
                          outputs=("_catalog",)))
    for mesh in ("chair.obj", "chair.glb", "chair.gltf", "chair.ply", "chair-ascii.ply", "chair.stl", "chair.off"):
        fmt = mesh.rsplit(".", 1)[1]
        out.append(Target("mesh", f"mesh:{mesh}", "meshes", mesh, fmt, _import("manifest.json"),
                          outputs=("_catalog",),
                          cli=lambda d: ["assets", "import", "meshes", str(d), "--manifest", str(d / "manifest.json"),
                                         "--library", str(d / "_catalog")]))
    out += [
        Target("scan", "scan:scan.npy", "scan", "scan.npy", "npy", _read_scan("scan.npy")),
        Target("scan", "scan:scan.ply", "scan", "scan.ply", "ply", _read_scan("scan.ply")),
        Target("scannet scene", "scannet:mesh.ply", "scannet", "scans/scene0000_00/scene0000_00_vh_clean_2.ply", "ply",
               _read_scannet),
        Target("scannet scene", "scannet:segs.json", "scannet", "scans/scene0000_00/scene0000_00_vh_clean_2.0.010000.segs.json",
               "json", _read_scannet),
        Target("scannet scene", "scannet:aggregation.json", "scannet", "scans/scene0000_00/scene0000_00.aggregation.json",
               "json", _read_scannet),
        Target("scannet scene", "scannet:labels.tsv", "scannet", "scannetv2-labels.combined.tsv", "text", _read_scannet),
        Target("predictions", "predictions:npz", "predictions", "scene_000000.npz", "npz", _read_npz_predictions),
        Target("predictions", "predictions:txt", "predictions", "txt/scene_000000.txt", "text",
               _read_txt_predictions),
        Target("predictions", "predictions:mask", "predictions", "txt/pred_mask/scene_000000_000.txt", "text",
               _read_txt_predictions),
        Target("checkpoint", "checkpoint:model.pt", "checkpoint", "model.pt", "pt", _read_checkpoint),
        Target("dataset", "dataset:manifest.json", "dataset", "manifest.json", "json", _read_dataset,
               cli=lambda d: ["metrics", str(d), "--max-scenes", "1"]),
        Target("dataset", "dataset:meta.json", "dataset", f"{scene}/meta.json", "json", _read_dataset),
        Target("dataset", "dataset:layout.json", "dataset", f"{scene}/layout.json", "json", _read_dataset),
        Target("dataset", "dataset:coord.npy", "dataset", f"{scene}/coord.npy", "npy", _read_dataset),
        Target("dataset", "dataset:instance.npy", "dataset", f"{scene}/instance.npy", "npy", _read_dataset),
    ]
    assert all((examples / t.folder / t.file).is_file() for t in out), [t.name for t in out]
    assert ds.is_dir()
    return out


# ------------------------------------------------------------------------------------------------
# mutations: (new bytes, must the reader refuse them?, what was done)

TEXT = {"yaml", "json", "csv", "text", "obj", "off", "gltf"}


def _truncate(data: bytes, fmt: str, rng: random.Random) -> tuple[bytes, bool, str]:
    cut = rng.randrange(0, max(1, len(data)))
    if rng.random() < 0.2:
        cut = rng.choice([0, 1, len(data) // 2, max(0, len(data) - 1)])
    # a cut binary file is damage a reader must see; a cut text file may still be a valid (shorter) one
    must = fmt in ("npy", "npz", "pt", "glb", "stl") or (fmt == "ply" and not data.startswith(b"ply\nformat ascii")) \
        or (cut == 0 and fmt != "yaml")  # an empty config is a valid one (all defaults)
    return data[:cut], must and cut < len(data), f"cut at byte {cut} of {len(data)}"


def _flip(data: bytes, fmt: str, rng: random.Random) -> tuple[bytes, bool, str]:
    b = bytearray(data)
    k = rng.choice([1, 1, 2, 4, 16])
    at = sorted(rng.randrange(len(b)) for _ in range(k)) if b else []
    for i in at:
        b[i] ^= 1 << rng.randrange(8)
    return bytes(b), False, f"{k} bit flip(s) at {at[:4]}{'...' if k > 4 else ''}"


def _encoding(data: bytes, fmt: str, rng: random.Random) -> tuple[bytes, bool, str]:
    if fmt in TEXT or (fmt == "ply" and data.startswith(b"ply\nformat ascii")):
        text = data.decode("utf-8", "replace")
        enc = rng.choice(["utf-16", "utf-16-le", "latin-1", "cp1252", "utf-32"])
        if enc in ("latin-1", "cp1252"):  # add a character those encodings write as a non-UTF-8 byte
            lines = text.split("\n")
            i = rng.randrange(len(lines))
            j = rng.randrange(len(lines[i]) + 1)
            lines[i] = lines[i][:j] + rng.choice("éüßø") + lines[i][j:]
            text = "\n".join(lines)
        # our own text formats are UTF-8: any other encoding must be refused; a mesh's text may hold
        # other 8-bit encodings in its comments and names (common in the wild), but never UTF-16 / 32
        # (glTF is JSON: UTF-16 / 32 JSON is still readable JSON, Latin-1 bytes are not)
        must = (fmt not in ("obj", "off", "ply", "gltf") or (fmt != "gltf" and enc.startswith("utf-"))
                or (fmt == "gltf" and not enc.startswith("utf-")))
        return text.encode(enc, "replace"), must, f"re-encoded as {enc}"
    if fmt == "npy":  # the other byte order: the same bytes read as other numbers
        new = data.replace(b"'<", b"'>", 1) if b"'<" in data[:128] else data.replace(b"'>", b"'<", 1)
        return new, False, "byte order swapped in the header"
    if fmt == "ply":
        if b"binary_little_endian" in data[:400]:
            return data.replace(b"binary_little_endian", b"binary_big_endian", 1), False, "byte order swapped"
        return data.replace(b"binary_big_endian", b"binary_little_endian", 1), False, "byte order swapped"
    # archives (npz, pt, glb, stl): a UTF-16 byte-order mark in front, as an editor would write
    # (a zip archive is read from its end: npz and pt may still be whole)
    return b"\xff\xfe" + data, fmt == "glb", "a UTF-16 byte-order mark prepended"


def _inflate(data: bytes, fmt: str, rng: random.Random) -> tuple[bytes, bool, str]:
    factor = rng.choice([2, 1000, 10**6, 10**12])
    if fmt in ("ply",) or (fmt == "off"):
        import re

        pat = rb"(element \w+ )(\d+)" if fmt == "ply" else rb"\A(\s*OFF\s+)(\d+)"
        m = list(re.finditer(pat, data[:4096]))
        if m:
            g = rng.choice(m)
            n = int(g.group(2)) * factor + 1
            return data[:g.start(2)] + str(n).encode() + data[g.end(2):], True, f"count {g.group(2).decode()} -> {n}"
    if fmt == "stl" and len(data) >= 84:
        n = struct.unpack("<I", data[80:84])[0]
        new = min(2**32 - 1, n * factor + 1)
        return data[:80] + struct.pack("<I", new) + data[84:], True, f"triangle count {n} -> {new}"
    if fmt == "npy" and b"'shape': (" in data[:256]:
        i = data.index(b"'shape': (") + 10
        j = data.index(b",", i)
        n = int(data[i:j]) * factor + 1
        hdr_end = data.index(b"\n", 0, 4096)
        new = data[:i] + str(n).encode() + data[j:hdr_end]
        pad = (64 - (len(new) + 1) % 64) % 64  # keep the header's 64-byte alignment and its stated length
        new = new.rstrip(b" ") + b" " * pad + b"\n"
        body = new[10:]
        new = new[:8] + struct.pack("<H", len(body)) + body if data[6] == 1 else new
        return new + data[hdr_end + 1:], True, f"rows {int(data[i:j])} -> {n}"
    if fmt == "npz":
        import zipfile

        with zipfile.ZipFile(io.BytesIO(data)) as z:
            members = {n: z.read(n) for n in z.namelist()}
        name = rng.choice(sorted(members))
        new, must, what = _inflate(members[name], "npy", rng)
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", zipfile.ZIP_STORED) as z:
            for n, v in members.items():
                z.writestr(n, new if n == name else v)
        return buf.getvalue(), must, f"{name}: {what}"
    if fmt in TEXT:  # numbers made huge
        import re

        nums = list(re.finditer(rb"(?<![\w.])\d+(?![\w.])", data))
        if nums:
            g = rng.choice(nums)
            n = int(g.group()) * factor + rng.choice([0, 10**30])
            return data[:g.start()] + str(n).encode() + data[g.end():], False, f"number {g.group().decode()} -> {n}"
    return _flip(data, fmt, rng)


def _nest(data: bytes, fmt: str, rng: random.Random) -> tuple[bytes, bool, str]:
    import re

    levels = rng.choice([50, 101, 1000, 5000, 100_000])
    if fmt == "yaml":
        text = data.decode("utf-8", "replace")
        lines = [ln for ln in text.split("\n")]
        keys = [i for i, ln in enumerate(lines) if re.match(r"^\s*[\w.-]+: [^#]*$", ln)]  # not in a comment
        if keys and rng.random() < 0.5:
            i = rng.choice(keys)
            k, v = lines[i].split(": ", 1)
            lines[i] = f"{k}: " + "[" * levels + v + "]" * levels
            return "\n".join(lines).encode(), levels > 100, f"a value nested {levels} levels"
        return f"deep: {'[' * levels}{']' * levels}\n".encode() + data, levels > 100, f"a key nested {levels} levels"
    if fmt in ("json", "gltf"):
        try:
            obj = json.loads(data)
        except ValueError:
            obj = None
        if obj is None or rng.random() < 0.4:
            return b"[" * levels + data + b"]" * levels, levels > 100, f"the whole nested in {levels} lists"
        slots = []  # (container, key) of every value, breadth first, up to a few thousand
        queue = [obj]
        while queue and len(slots) < 5000:
            c = queue.pop(0)
            keys = list(c) if isinstance(c, dict) else range(len(c))
            for k in keys:
                slots.append((c, k))
                if isinstance(c[k], (dict, list)):
                    queue.append(c[k])
        if not slots:
            return b"[" * levels + data + b"]" * levels, levels > 100, f"the whole nested in {levels} lists"
        c, k = rng.choice(slots)
        c[k] = "__NESTED__"
        text = json.dumps(obj, indent=1).replace('"__NESTED__"', "[" * levels + "0" + "]" * levels, 1)
        return text.encode(), levels > 100, f"a value replaced by {levels} nested lists"
    if fmt == "csv":
        return data + b",".join([b'"' + b"[" * levels + b'"', b"chair"]) + b"\n", False, f"a row of {levels} brackets"
    if fmt == "npz":  # an archive inside the archive, as a member
        import zipfile

        buf = io.BytesIO()
        with zipfile.ZipFile(io.BytesIO(data)) as z, zipfile.ZipFile(buf, "w") as out:
            for n in z.namelist():
                out.writestr(n, z.read(n))
            out.writestr("inner.npy", data)
        return buf.getvalue(), False, "the archive added as a member of itself"
    if fmt in ("ply", "obj", "off", "stl", "glb", "npy", "pt", "text"):  # the file repeated inside itself
        k = rng.choice([2, 10])
        # an array file is exactly its header's shape: more bytes are damage (other formats may hold
        # concatenated copies validly: a zip is read from its end, an OBJ may list a mesh twice)
        return data * k, fmt == "npy", f"the file repeated {k} times"
    return _flip(data, fmt, rng)


MUTATE = {"truncate": _truncate, "flip": _flip, "encoding": _encoding, "inflate": _inflate, "nest": _nest}


# ------------------------------------------------------------------------------------------------
# running one case


@dataclass
class Outcome:
    index: int
    target: str
    kind: str
    operator: str
    what: str
    cls: str
    note: str
    seconds: float
    cli: str = ""


@dataclass
class Plan:
    index: int
    target: Target
    operator: str
    seed: int
    force: tuple = ()  # parameter values chosen whenever the mutation draws among them (the families)


class _Draws(random.Random):
    """The case's generator; ``choice`` takes a forced value when the choices offer one."""

    def __init__(self, seed: str, force: tuple = ()) -> None:
        super().__init__(seed)
        self.force = force

    def choice(self, seq):
        for f in self.force:
            if f in seq:
                return f
        return super().choice(seq)


#: the damage that ended in tracebacks before the reading layer (issue 54's first families), always
#: run after the seeded cases: (target, operator, forced parameters)
FAMILIES = (
    ("config:generate.yaml", "encoding", ("latin-1",)),
    ("config:generate.yaml", "nest", (5000,)),
    ("dataset:manifest.json", "nest", (100_000,)),
)


def plan(all_targets: list[Target], cases: int, seed: int, only: str | None = None) -> list[Plan]:
    ts = [t for t in all_targets if not only or only in t.name or only == t.kind]
    out = []
    for i in range(cases):
        t = ts[i % len(ts)]
        op = OPERATORS[(i // len(ts)) % len(OPERATORS)]
        out.append(Plan(i, t, op, seed))
    return out


def family_plans(all_targets: list[Target], seed: int, first: int) -> list[Plan]:
    """The :data:`FAMILIES`, numbered from ``first``."""
    by_name = {t.name: t for t in all_targets}
    return [Plan(first + k, by_name[name], op, seed, force) for k, (name, op, force) in enumerate(FAMILIES)]


def slice_indices(n_targets: int) -> list[int]:
    """One case per target, the operators taking turns (every target and operator at least once)."""
    return [t + n_targets * (t % len(OPERATORS)) for t in range(n_targets)]


def _digest(folder: Path, outputs: tuple[str, ...]) -> dict[str, str]:
    out = {}
    for p in sorted(folder.rglob("*")):
        rel = p.relative_to(folder).as_posix()
        if p.is_file() and not any(rel == o or rel.startswith(o + "/") for o in outputs):
            out[rel] = hashlib.sha256(p.read_bytes()).hexdigest()
    return out


class _Warnings(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.lines: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.lines.append(record.getMessage())
        except Exception:  # noqa: BLE001 - a malformed log call is not the case's outcome
            self.lines.append(str(record.msg))


def _child(target: Target, folder: Path, w) -> None:
    """Run in the forked child: the reading, its result as one JSON line on ``w``."""
    from assist3d.core.errors import AssistError

    handler = _Warnings()
    for name in ("", "assist3d"):  # the command line's logger may not propagate to the root
        lg = logging.getLogger(name)
        lg.addHandler(handler)
        lg.setLevel(logging.WARNING)
        lg.disabled = False
    try:
        target.read(folder)
        res = {"r": "ok", "warnings": handler.lines}
    except AssistError as e:
        res = {"r": "error", "msg": str(e), "warnings": handler.lines}
    except BaseException as e:  # noqa: BLE001 - what a user would see as a traceback
        res = {"r": "exception", "msg": f"{type(e).__name__}: {e}"[:500], "warnings": handler.lines}
    res["msg"] = res.get("msg", "")[:2000]
    res["warnings"] = [x[:500] for x in res["warnings"][:20]]
    data = json.dumps(res).encode()
    while data:
        data = data[os.write(w, data):]


def _memory_cap() -> None:
    """The child's address space: what it has now plus 3 GiB (a forged size hits this, not the machine)."""
    try:
        with open("/proc/self/status") as f:
            vm = next(int(ln.split()[1]) * 1024 for ln in f if ln.startswith("VmSize:"))
        resource.setrlimit(resource.RLIMIT_AS, (vm + (3 << 30), vm + (3 << 30)))
    except (OSError, ValueError, StopIteration):
        pass


def run_in_child(target: Target, folder: Path, timeout: float) -> tuple[str, dict | None, float]:
    """('done', result, s) or ('hang', None, s) or ('died', {'msg'}, s)."""
    r, w = os.pipe()
    t0 = time.monotonic()
    pid = os.fork()
    if pid == 0:  # child
        try:
            os.close(r)
            _memory_cap()
            _child(target, folder, w)
        finally:
            os._exit(0)
    os.close(w)
    chunks: list[bytes] = []
    deadline = t0 + timeout
    import select

    status = None
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            os.close(r)
            return "hang", None, time.monotonic() - t0
        ready, _, _ = select.select([r], [], [], min(left, 0.5))
        if ready:
            chunk = os.read(r, 65536)
            if chunk:
                chunks.append(chunk)
                continue
            _, status = os.waitpid(pid, 0)
            break
    os.close(r)
    seconds = time.monotonic() - t0
    if not chunks:
        sig = os.WTERMSIG(status) if os.WIFSIGNALED(status) else None
        return "died", {"msg": f"the child died (signal {sig}, status {status})"}, seconds
    return "done", json.loads(b"".join(chunks)), seconds


def _names(msg: str, folder: Path, file: str) -> bool:
    """Does an error's first line name the file, or a folder on its path inside the case folder?"""
    first = msg.split("\n", 1)[0]
    parts = Path(file).parts
    candidates = [Path(file).name] + [str(folder / Path(*parts[:k])) for k in range(1, len(parts))] + [str(folder)]
    return any(c in first for c in candidates)


def classify(p: Plan, folder: Path, must: bool, state: str, res: dict | None, changed: list[str]) -> tuple[str, str]:
    if state == "hang":
        return "hang", "time limit"
    if state == "died":
        return "traceback", res["msg"]
    if changed:
        return "loss", f"changed: {', '.join(changed[:3])}"
    if res["r"] == "exception":
        return "traceback", res["msg"].split("\n")[0][:200]
    if res["r"] == "error":
        if _names(res["msg"], folder, p.target.file):
            return "clear", res["msg"].split("\n")[0][:200]
        return "unclear", res["msg"].split("\n")[0][:200]
    warned = [w for w in res["warnings"] if _names(w, folder, p.target.file) or str(folder) in w]
    if warned:
        return "clear", "accepted with a warning: " + warned[0].split("\n")[0][:160]
    if must:
        return "silent", "accepted without a word"
    return "clear", "accepted (the damage left a valid file)"


def run_case(p: Plan, examples: Path, work: Path, timeout: float, cli: bool = False) -> Outcome:
    rng = _Draws(f"{p.seed}:{p.index}", p.force)
    folder = work / f"case{p.index:05d}"
    shutil.rmtree(folder, ignore_errors=True)
    shutil.copytree(examples / p.target.folder, folder)
    path = folder / p.target.file
    data, must, what = MUTATE[p.operator](path.read_bytes(), p.target.fmt, rng)
    path.write_bytes(data)
    before = _digest(folder, p.target.outputs)
    state, res, seconds = run_in_child(p.target, folder, timeout)
    after = _digest(folder, p.target.outputs)
    changed = sorted(k for k in before if after.get(k) != before[k])
    cls, note = classify(p, folder, must, state, res, changed)
    cli_cls = ""
    if cli and p.target.cli is not None:
        cli_cls = run_cli(p.target.cli(folder), folder, p.target.file)
    shutil.rmtree(folder, ignore_errors=True)
    return Outcome(p.index, p.target.name, p.target.kind, p.operator, what, cls, note.replace(str(folder), "CASE"),
                   round(seconds, 3), cli_cls)


def run_cli(argv: list[str], folder: Path, file: str, timeout: float = 120.0) -> str:
    """The command line itself: 'clear' for exit 0 or an error line without a traceback."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    try:
        proc = subprocess.run([sys.executable, "-m", "assist3d", *argv], capture_output=True, env=env,
                              timeout=timeout, cwd=folder, start_new_session=True)
    except subprocess.TimeoutExpired:
        return "hang"
    text = (proc.stdout + proc.stderr).decode("utf-8", "replace")
    if "Traceback (most recent call last)" in text:
        return "traceback"
    if proc.returncode == 0:
        return "clear"
    return "clear" if _names(text, folder, file) or str(folder) in text else "unclear"


# ------------------------------------------------------------------------------------------------
# the whole run


def fuzz(cases: int, seed: int, *, only: str | None = None, case: int | None = None, cli: int = 0,
         timeout: float = 30.0, examples: Path | None = None, progress: bool = False,
         one_each: bool = False, families: bool = True) -> list[Outcome]:
    """Build the examples (unless given), run the cases (``one_each``: instead one case per target,
    see :func:`slice_indices`) and the :data:`FAMILIES`, return their outcomes."""
    with tempfile.TemporaryDirectory(prefix="assist3d-fuzz-files-") as tmp:
        tmp_path = Path(tmp)
        if examples is None:
            examples = tmp_path / "examples"
            env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "OMP_NUM_THREADS": "1"}
            subprocess.run([sys.executable, str(Path(__file__).resolve()), "--build", str(examples)], check=True,
                           env=env)
        os.environ["ASSIST3D_CACHE"] = str(tmp_path / "cache")  # the children never touch the user's cache
        _warm_imports()
        all_targets = targets(examples)
        baseline(all_targets, examples, tmp_path / "baseline", timeout)
        if one_each:
            cases = len(all_targets) * len(OPERATORS)
        plans = plan(all_targets, cases if case is None else case + 1, seed, only)
        if case is not None:
            plans = plans[case:case + 1]
        elif one_each:
            plans = [plans[i] for i in slice_indices(len(all_targets))]
        if families and case is None and not only:
            plans += family_plans(all_targets, seed, cases)
        work = tmp_path / "work"
        work.mkdir()
        out = []
        for k, p in enumerate(plans):
            o = run_case(p, examples, work, timeout, cli=k < cli)
            out.append(o)
            if progress:
                print(f"{o.index:5d} {o.target:26s} {o.operator:9s} {o.cls:9s} {o.seconds:6.2f}s {o.note[:90]}",
                      flush=True)
        return out


def baseline(all_targets: list[Target], examples: Path, work: Path, timeout: float) -> None:
    """Every target read from its unmutated example: a result and no warning, else the examples are
    wrong (and every case of that target would measure the wrong thing)."""
    work.mkdir()
    for t in all_targets:
        folder = work / t.name.replace(":", "-")
        shutil.copytree(examples / t.folder, folder)
        state, res, _ = run_in_child(t, folder, timeout)
        if state != "done" or res["r"] != "ok" or res["warnings"]:
            raise SystemExit(f"the valid example of {t.name} does not read cleanly: {state} {res}")
        shutil.rmtree(folder)


def _warm_imports() -> None:
    """Import what the readers use once, so each forked child starts warm."""
    import assist3d.assets.catalog  # noqa: F401
    import assist3d.assets.meshes  # noqa: F401
    import assist3d.data  # noqa: F401
    import assist3d.bench.evaluation.predictions  # noqa: F401
    import assist3d.bench.metrics.report  # noqa: F401
    import assist3d.cli.segment  # noqa: F401
    import assist3d.config.presets  # noqa: F401
    import assist3d.learn.engine.config  # noqa: F401
    import assist3d.learn.segmenter.checkpoint  # noqa: F401
    import trimesh  # noqa: F401


def table(outcomes: list[Outcome]) -> str:
    """Markdown: cases per kind (rows) and outcome (columns), then per operator."""
    lines = []
    for key, title in (("kind", "kind"), ("operator", "operator")):
        rows = sorted({getattr(o, key) for o in outcomes}, key=lambda k: (key == "operator" and OPERATORS.index(k), k))
        lines.append(f"| {title} | cases | " + " | ".join(CLASSES) + " |")
        lines.append("| --- | ---: | " + " | ".join("---:" for _ in CLASSES) + " |")
        for r in rows:
            c = Counter(o.cls for o in outcomes if getattr(o, key) == r)
            lines.append(f"| {r} | {sum(c.values())} | " + " | ".join(str(c.get(k, 0)) for k in CLASSES) + " |")
        c = Counter(o.cls for o in outcomes)
        lines.append(f"| **all** | **{len(outcomes)}** | " + " | ".join(f"**{c.get(k, 0)}**" for k in CLASSES) + " |")
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cases", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--only", help="run only the targets whose name contains this (or of this kind)")
    ap.add_argument("--case", type=int, help="run only case I (as numbered in a full run of the same seed)")
    ap.add_argument("--cli", type=int, default=0, help="also run the command line for the first N cases")
    ap.add_argument("--timeout", type=float, default=30.0, help="seconds per case before it counts as a hang")
    ap.add_argument("--json", type=Path, help="write the outcomes here")
    ap.add_argument("--examples", type=Path, help="use the examples already built in this folder (--build)")
    ap.add_argument("--build", type=Path, help="only build the examples into this folder")
    ap.add_argument("--quiet", action="store_true", help="no line per case")
    ap.add_argument("--slice", action="store_true", help="one case per target, the operators taking turns")
    args = ap.parse_args(argv)
    if args.build:
        logging.basicConfig(level=logging.ERROR)
        build_examples(args.build)
        return 0
    t0 = time.monotonic()
    outcomes = fuzz(args.cases, args.seed, only=args.only, case=args.case, cli=args.cli, timeout=args.timeout,
                    examples=args.examples, progress=not args.quiet,
                    one_each=args.slice)
    print()
    print(table(outcomes))
    bad = [o for o in outcomes if o.cls != "clear" or (o.cli and o.cli != "clear")]
    for o in bad:
        print(f"NOT CLEAR: case {o.index} {o.target} {o.operator} ({o.what}): {o.cls} {o.cli} {o.note}")
    clis = Counter(o.cli for o in outcomes if o.cli)
    if clis:
        print(f"command line: {dict(clis)}")
    print(f"{len(outcomes)} cases, seed {args.seed}, {time.monotonic() - t0:.0f} s: "
          + ", ".join(f"{Counter(o.cls for o in outcomes).get(k, 0)} {k}" for k in CLASSES))
    if args.json:
        args.json.write_text(json.dumps([o.__dict__ for o in outcomes], indent=1) + "\n")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
