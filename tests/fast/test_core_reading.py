"""The reading layer (``assist3d.core.reading``): every user file is read through it, each failure is
the project's own one-line error naming the file, and the documented bounds refuse a file before
the work starts."""

from __future__ import annotations

import ast
import io
import struct
import zipfile
from pathlib import Path

import numpy as np
import pytest

from assist3d.core import reading
from assist3d.core.errors import AssetError, ConfigError, DataError

SRC = Path(__file__).resolve().parents[2] / "src" / "assist3d"

#: (module path relative to src/assist3d, call) -> why it may read a file another way
ALLOWED: dict[tuple[str, str], str] = {
    ("core/reading.py", "*"): "the reading layer itself",
    ("core/fileio.py", "open"): "the atomic writer opens its temporary file for writing",
    ("core/bounds.py", "read_text"): "the cgroup memory limit under /sys/fs/cgroup, not a user file",
    ("core/interrupts.py", "open"): "/proc/<pid>/stat of the process's own children",
    ("testing.py", "*"): "test helpers reading outputs the tests just wrote",
    ("pipeline/ray_backend.py", "read_text"): "a token file this process wrote a moment before (shared-folder probe)",
    ("learn/engine/loggers.py", "open"): "appends rows to its own metrics.csv",
    ("learn/segmenter/probe.py", "open"): "a child process's log file, opened for writing",
    ("learn/segmenter/pack.py", "open"): "writes a scene pack's files (it reads them through np.memmap)",
    ("llm/schema.py", "json.loads"): "an LLM answer held in memory, not a file",
    ("llm/client.py", "json.loads"): "an HTTP response body held in memory, bounded by llm.max_response_bytes",
    ("data/s3dis.py", "np.loadtxt"): "parses bytes already read through the layer",
    ("core/taxonomy/classes.py", "read_text"): "a class list packaged with assist3d (importlib.resources)",
    ("llm/prompts.py", "read_text"): "a prompt template packaged with assist3d (importlib.resources)",
    ("bench/metrics/realism.py", "read_text"): "the reference packaged with assist3d (importlib.resources)",
    ("assets/meshes.py", "trimesh.load"): "parses mesh bytes read (and their counts checked) through the layer",
    ("assets/sh3d.py", "trimesh.load"): "parses an OBJ member of a Sweet Home 3D archive, already in memory",
    ("export/writer.py", "read_bytes"): "digests the files a scene marker lists (their sizes checked first)",
    ("core/taxonomy/scannet.py", "read_text"): "the ScanNet200 id table packaged with assist3d (importlib.resources)",
    ("view/page.py", "read_text"): "the viewer's script packaged with assist3d and plotly.js from the installed plotly",
    ("core/machine.py", "open"): "/proc/cpuinfo, the kernel's description of the CPU (not a user file), line by line",
}

#: attribute calls that read: obj.read_text(), obj.read_bytes(); module functions that read
READ_METHODS = {"read_text", "read_bytes"}
READ_FUNCS = {("json", "load"), ("json", "loads"), ("np", "load"), ("numpy", "load"), ("np", "loadtxt"),
              ("np", "fromfile"), ("torch", "load"), ("pickle", "load"), ("pickle", "loads"), ("trimesh", "load")}
#: yaml functions that write (everything else of ``yaml.`` reads or parses)
YAML_WRITERS = {"safe_dump", "dump", "YAMLError"}


def _stray_reads(path: Path) -> list[tuple[int, str]]:
    """(line, call) of every read in ``path`` that bypasses the layer."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "yaml" \
                and node.attr not in YAML_WRITERS:
            found.append((node.lineno, f"yaml.{node.attr}"))
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        if isinstance(f, ast.Name) and f.id == "open":
            found.append((node.lineno, "open"))
        elif isinstance(f, ast.Attribute) and not (isinstance(f.value, ast.Name) and f.value.id == "reading"):
            if f.attr in READ_METHODS:
                found.append((node.lineno, f.attr))
            elif isinstance(f.value, ast.Name) and (f.value.id, f.attr) in READ_FUNCS:
                arg = node.args[0] if node.args else None
                copy = (isinstance(arg, ast.Call) and isinstance(arg.func, ast.Attribute) and arg.func.attr == "dumps")
                if not copy:  # json.loads(json.dumps(x)) copies a value; it reads no file
                    found.append((node.lineno, f"{f.value.id}.{f.attr}"))
    return sorted(found)


def test_no_command_reads_a_user_file_outside_the_reading_layer():
    stray = []
    for p in sorted(SRC.rglob("*.py")):
        rel = p.relative_to(SRC).as_posix()
        for line, call in _stray_reads(p):
            if (rel, "*") in ALLOWED or (rel, call) in ALLOWED:
                continue
            stray.append(f"{rel}:{line}: {call}")
    assert not stray, "read these through assist3d.core.reading (or allow-list them with a reason):\n" + "\n".join(stray)


def test_the_stray_read_check_finds_each_kind_of_read(tmp_path):
    p = tmp_path / "m.py"
    p.write_text("import json, yaml\nimport numpy as np\n"
                 "a = open('x')\nb = P.read_text()\nc = yaml.safe_load(s)\nd = json.load(f)\ne = np.load('y')\n"
                 "f = yaml.safe_dump(d)\ng = json.loads(json.dumps(d))\n")
    assert [c for _, c in _stray_reads(p)] == ["open", "read_text", "yaml.safe_load", "json.load", "np.load"]


def test_allow_list_entries_are_still_needed():
    """An allow-list entry whose read is gone must leave the list (it stays short)."""
    used = set()
    for p in sorted(SRC.rglob("*.py")):
        rel = p.relative_to(SRC).as_posix()
        for _, call in _stray_reads(p):
            used |= {(rel, call), (rel, "*")}
    assert set(ALLOWED) <= used, sorted(set(ALLOWED) - used)


# ------------------------------------------------------------------------------------------------
# The readers: one line naming the file, bounds refused before the work


def _one_line(err: pytest.ExceptionInfo, path: Path) -> str:
    msg = str(err.value)
    assert msg.startswith(f"{path}: ") and "\n" not in msg, msg
    return msg


def test_text_in_another_encoding_names_the_byte_and_binary_files_are_refused(tmp_path):
    p = tmp_path / "c.yaml"
    p.write_bytes("name: café\n".encode("utf-16"))
    with pytest.raises(ConfigError) as e:
        reading.read_yaml(p, error=ConfigError)
    assert "not UTF-8 text: byte 0" in _one_line(e, p) and "UTF-16" in str(e.value)
    p.write_bytes(b"a: 1\n\0\0\0")
    with pytest.raises(DataError, match="NUL byte"):
        reading.read_text(p)
    p.write_bytes("\ufeffa: 1\n".encode("utf-8"))  # a byte-order mark is text
    assert reading.read_yaml(p) == {"a": 1}


def test_yaml_depth_and_expanded_size_are_refused_from_the_event_stream(tmp_path):
    p = tmp_path / "c.yaml"
    p.write_text("a: " + "[" * 101 + "]" * 101)
    with pytest.raises(DataError) as e:
        reading.read_yaml(p)
    assert "nested too deeply (more than 100 levels)" in _one_line(e, p)
    p.write_text("a: " + "[" * 99 + "]" * 99)  # 100 levels with the top mapping: accepted
    assert isinstance(reading.read_yaml(p)["a"], list)
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]" for i in range(1, 9)]  # 10^9 values
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError) as e:
        reading.read_yaml(p)
    assert "aliases" in _one_line(e, p)
    p.write_text("a: &x [*x]\n")
    with pytest.raises(DataError, match="cycle"):
        reading.read_yaml(p)
    p.write_text("x: &v [1, 2]\ny: *v\n")  # a plain alias is fine
    assert reading.read_yaml(p) == {"x": [1, 2], "y": [1, 2]}
    p.write_text("a: 1\n" + "#" * 200)
    with pytest.raises(DataError, match="more than the 100 bytes"):
        reading.read_yaml(p, limit=100)


def test_json_size_and_depth_bounds(tmp_path):
    p = tmp_path / "m.json"
    p.write_text("[" * 50_000 + "]" * 50_000)
    with pytest.raises(DataError) as e:
        reading.read_json(p)
    assert "nested too deeply" in _one_line(e, p)
    p.write_text('{"a": [1, 2, 3]}')
    assert reading.read_json(p) == {"a": [1, 2, 3]}
    with pytest.raises(DataError, match="16 bytes, more than the 10 bytes"):
        reading.read_json(p, limit=10)
    p.write_text('{"a": 1')
    with pytest.raises(AssetError, match="bad JSON at line 1"):
        reading.read_json(p, error=AssetError)
    with pytest.raises(DataError, match="is a folder"):
        reading.read_json(tmp_path)


def test_npz_members_are_checked_against_their_headers_before_decompressing(tmp_path):
    p = tmp_path / "a.npz"
    np.savez_compressed(p, masks=np.ones((3, 5), bool), scores=np.arange(3, dtype=np.float32))
    z = reading.read_npz(p, keys=("masks", "scores"))
    assert z["masks"].shape == (3, 5) and z["scores"].flags.writeable
    # a member whose header claims 10^12 rows: refused from the header, nothing allocated
    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f4", "fortran_order": False, "shape": (10**12, 3)})
    with zipfile.ZipFile(p, "w") as zf:
        zf.writestr("scores.npy", buf.getvalue() + b"\0" * 64)
    with pytest.raises(DataError) as e:
        reading.read_npz(p)
    assert "more than the" in _one_line(e, p)
    np.lib.format.write_array_header_1_0(buf := io.BytesIO(), {"descr": "<f4", "fortran_order": False, "shape": (100,)})
    with zipfile.ZipFile(p, "w") as zf:
        zf.writestr("scores.npy", buf.getvalue() + b"\0" * 64)
    with pytest.raises(DataError, match="truncated"):
        reading.read_npz(p)
    np.lib.format.write_array_header_1_0(buf := io.BytesIO(), {"descr": "|O", "fortran_order": False, "shape": (1,)})
    with zipfile.ZipFile(p, "w") as zf:
        zf.writestr("obj.npy", buf.getvalue() + b"\0" * 64)
    with pytest.raises(DataError, match="never pickles"):
        reading.read_npz(p)


def test_mesh_headers_claiming_more_than_the_file_holds_are_refused(tmp_path):
    ply = (b"ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000\nproperty float x\n"
           b"property float y\nproperty float z\nend_header\n" + b"\0" * 120)
    with pytest.raises(DataError, match=r"m\.ply: truncated PLY: its header claims vertex 1,000,000,000,000"):
        reading.check_mesh_counts(ply, "ply", tmp_path / "m.ply")
    ascii_ply = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
    with pytest.raises(DataError, match="truncated PLY"):
        reading.check_mesh_counts(ascii_ply + b"0 0 0\n", "ply", "m.ply")
    reading.check_mesh_counts(ascii_ply + b"0 0 0\n" * 4, "ply", "m.ply")
    with pytest.raises(DataError, match="OFF header claims 99,999,999 vertices"):
        reading.check_mesh_counts(b"OFF\n99999999 1 0\n0 0 0\n3 0 0 0\n", "off", "m.off")
    stl = b"\0" * 80 + struct.pack("<I", 10**9) + b"\0" * 50
    with pytest.raises(DataError, match="binary STL header claims 1,000,000,000 triangles"):
        reading.check_mesh_counts(stl, "stl", "m.stl")
    big = (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
           b"property float z\nelement face 60000000\nproperty list uchar int vertex_indices\nend_header\n")
    with pytest.raises(DataError, match="60,000,000 faces, more than the 50,000,000"):
        reading.check_mesh_counts(big + b"\0" * (36 + 60_000_000), "ply", "m.ply")


def test_checkpoints_that_are_not_archives_or_hold_objects_are_one_line(tmp_path):
    pytest.importorskip("torch")
    import pickle

    p = tmp_path / "m.pt"
    p.write_bytes(b"not a zip")
    with pytest.raises(DataError) as e:
        reading.read_checkpoint(p)
    assert "not a PyTorch archive" in _one_line(e, p)
    import torch

    torch.save({"a": torch.ones(2)}, p)
    assert torch.equal(reading.read_checkpoint(p)["a"], torch.ones(2))
    torch.save({"a": Path("x")}, p)  # any object other than tensors / numbers / text
    with pytest.raises(DataError, match="refused: the file holds objects other than tensors"):
        reading.read_checkpoint(p)
    assert pickle  # the restricted unpickler refused it; nothing ran


def test_a_damaged_npy_header_is_one_line_whatever_numpy_raises(tmp_path):
    """A flipped bit in a header's dict literal made numpy's tokenizer raise TokenError (found by
    scripts/fuzz_files.py, case 629 of seed 0)."""
    buf = io.BytesIO()
    np.save(buf, np.arange(3, dtype=np.float32))
    raw = bytearray(buf.getvalue())
    raw[raw.index(b"}")] = ord(" ")  # the dict never closes: numpy's tokenizer raises TokenError
    p = tmp_path / "a.npz"
    with zipfile.ZipFile(p, "w") as zf:
        zf.writestr("scores.npy", bytes(raw))
    with pytest.raises(DataError) as e:
        reading.read_npz(p)
    assert "not a readable .npy array" in _one_line(e, p)


def test_a_mesh_past_the_triangle_bound_is_skipped_with_its_reason(tmp_path, monkeypatch):
    """Formats whose header states no count (OBJ, GLB) are bounded once loaded, before normalising."""
    import json

    from assist3d.assets.catalog import Catalog
    from assist3d.assets.meshes import import_meshes

    folder = tmp_path / "m"
    folder.mkdir()
    (folder / "box.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 2 5\n")
    (folder / "manifest.json").write_text(json.dumps([{"path": "box.obj", "class": "box", "size": "1,1,1"}]))
    monkeypatch.setattr(reading, "MAX_MESH_TRIANGLES", 2)
    report = import_meshes(Catalog(tmp_path / "cat"), folder, folder / "manifest.json", workers=1)
    assert not any(report.added.values()) and len(report.skipped) == 1
    assert "box.obj" in report.skipped[0].path and "3 triangles, more than the" in report.skipped[0].reason
