"""Faults get one line and a way forward (issue 17, item 4) and every number has a bound (item 6).

Disk full on a small tmpfs and read-only mounts need ``mount`` (root); permission denied needs a
process without root's permission bypass (``setpriv`` drops it). Those tests skip, saying why,
where the machine forbids them; ``/dev/full`` stands in for a full disk everywhere on Linux.
"""

from __future__ import annotations

import errno
import json
import os
import re
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from assist3d.core.bounds import MAX_SCENES, check_render_memory, check_scene_indices, render_memory_bytes
from assist3d.cli import app
from assist3d.config import parse_config
from assist3d.core.errors import ConfigError, DataError, FaultError, describe_os_error
from assist3d.export import read_scene_meta
from assist3d.core.fileio import atomic_path, write_bytes_atomic
from assist3d.pipeline import generate_dataset, scene_name
from assist3d.testing import dataset_digest
from test_pipeline_generate import TINY

LINUX = sys.platform.startswith("linux")
runner = CliRunner()
GIB = 2**30


# ------------------------------------------------------------------------------------------------
# helpers


digest = dataset_digest


def cli(*args: str, prefix: tuple[str, ...] = (), timeout: float = 120) -> subprocess.CompletedProcess:
    """The real command line (its top-level error handler included) in a subprocess."""
    env = {**os.environ, "COLUMNS": "2000"}  # one message, one line (rich wraps at the terminal width)
    return subprocess.run([*prefix, sys.executable, "-m", "assist3d", "-q", *args], capture_output=True, text=True,
                          timeout=timeout, env=env)


def one_error_line(res: subprocess.CompletedProcess) -> str:
    """The single ERROR line of a run ended by a fault of the machine (exit 1, no traceback)."""
    assert res.returncode == 1, (res.returncode, res.stdout + res.stderr)
    assert "Traceback" not in res.stderr, res.stderr
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("ERROR")]
    assert len(lines) == 1, res.stderr
    return " ".join(lines[0].split())


def _mount_problem() -> str | None:
    if not LINUX:
        return "tmpfs mounts need Linux"
    if os.geteuid() != 0:
        return "mounting a tmpfs needs root"
    if shutil.which("mount") is None:
        return "no mount command"
    return None


@pytest.fixture
def tmpfs(tmp_path):
    """``make(size, read_only=False) -> Path``: a tmpfs mounted under tmp_path (unmounted after)."""
    why = _mount_problem()
    if why:
        pytest.skip(why)
    mounted: list[Path] = []

    def make(size: str, read_only: bool = False) -> Path:
        p = tmp_path / f"mnt{len(mounted)}"
        p.mkdir()
        opts = f"size={size}" + (",ro" if read_only else "")
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(p)], capture_output=True, text=True)
        if r.returncode != 0:
            pytest.skip(f"this machine does not allow a tmpfs mount: {r.stderr.strip()}")
        mounted.append(p)
        return p

    yield make
    for p in reversed(mounted):
        subprocess.run(["umount", "-l", str(p)], capture_output=True)


@pytest.fixture(scope="module")
def tiny_cfg_file(tmp_path_factory) -> Path:
    p = tmp_path_factory.mktemp("cfg") / "tiny.yaml"
    p.write_text(yaml.safe_dump(TINY))
    return p


@pytest.fixture(scope="module")
def reference4(tmp_path_factory) -> dict[str, str]:
    out = tmp_path_factory.mktemp("ref4")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("ASSIST3D_CACHE", str(tmp_path_factory.getbasetemp() / "assist3d-cache"))
        mp.delenv("ASSIST3D_ASSETS", raising=False)
        generate_dataset(parse_config(TINY), out, range(4))
    return digest(out)


# ------------------------------------------------------------------------------------------------
# one line per fault


def _raised(fn) -> OSError:
    with pytest.raises(OSError) as err:
        fn()
    return err.value


def test_each_fault_is_one_line_naming_the_path_and_a_way_forward(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("x")
    folder = tmp_path / "folder"
    folder.mkdir()
    under = describe_os_error(_raised(lambda: (afile / "sub" / "x.png").parent.mkdir(parents=True)))
    assert under == f"{afile}: is a file where a folder is expected; remove the file or choose another path"
    opened = describe_os_error(_raised(lambda: open(afile / "x.png", "wb")))
    assert opened.startswith(f"{afile}: is a file where a folder is expected")
    renamed = describe_os_error(_raised(lambda: os.replace(afile, folder)))
    assert renamed == f"{folder}: is a folder, expected a file; give a file path"
    full = describe_os_error(OSError(errno.ENOSPC, "No space left on device", str(tmp_path / "o.npy")))
    assert full == f"{tmp_path / 'o.npy'}: no space left on the device; free some space or choose another folder"
    ro = describe_os_error(OSError(errno.EROFS, "Read-only file system", "/mnt/x"))
    assert ro == "/mnt/x: read-only file system; choose a writable folder"
    denied = describe_os_error(PermissionError(errno.EACCES, "Permission denied", "/x\x1b[2J"))
    assert denied == "/x\\x1b[2J: permission denied; check the permissions or choose another folder"
    for msg in (under, renamed, full, ro, denied):
        assert "\n" not in msg


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="no /dev/full on this machine")
def test_dev_full_write_names_the_target_and_leaves_no_temporary_file(tmp_path):
    target = tmp_path / "out.npy"
    with pytest.raises(OSError) as err:
        with atomic_path(target) as tmp:
            assert tmp.parent == tmp_path
            with open("/dev/full", "wb") as f:  # the disk is full as this file is written
                f.write(b"\0" * 65536)
                f.flush()
    assert err.value.errno == errno.ENOSPC and err.value.filename == str(target)
    assert describe_os_error(err.value) == (f"{target}: no space left on the device; free some space or choose "
                                            f"another folder")
    assert list(tmp_path.iterdir()) == []


def test_an_output_path_that_is_a_device_is_refused_not_replaced(tmp_path):
    node = tmp_path / "full"
    try:
        os.mknod(node, 0o666 | stat.S_IFCHR, os.makedev(1, 7))  # a /dev/full of our own
    except (OSError, AttributeError) as e:
        pytest.skip(f"cannot make a device node here: {e}")
    with pytest.raises(DataError, match=r"full: is not a regular file \(a device, pipe or socket\)"):
        write_bytes_atomic(node, b"data")
    assert node.is_char_device() and sorted(p.name for p in tmp_path.iterdir()) == ["full"]


@pytest.mark.slow
def test_the_command_line_answers_a_file_where_a_folder_is_expected_in_one_line(tmp_path, tiny_cfg_file):
    afile = tmp_path / "afile"
    afile.write_text("x")
    line = one_error_line(cli("layout", "--config", str(tiny_cfg_file), "--no-glb", "--out", str(afile / "x")))
    assert line == f"ERROR {afile}: is a file where a folder is expected; remove the file or choose another path"
    res = cli("generate", "--config", str(tiny_cfg_file), "-n", "1", "--out", str(afile / "data"))
    line = one_error_line(res)
    assert str(afile) in line and "is a file where a folder is expected" in line


def test_generate_fault_mid_run_says_what_is_complete_and_keeps_it(tmp_path, monkeypatch):
    """An OSError while writing scene 1 of 3: scene 0 stays complete, scene 1's half-written
    folder goes, and the message counts the complete scenes and says how to resume."""
    from assist3d.export import writer
    from assist3d.pipeline import scene as pipeline_scene

    real = writer.write_scene

    def full_at_scene_1(scene_dir, *a, **kw):
        if Path(scene_dir).name == scene_name(1):
            Path(scene_dir).mkdir(parents=True)
            (Path(scene_dir) / "coord.npy").write_bytes(b"half")
            raise OSError(errno.ENOSPC, "No space left on device", str(Path(scene_dir) / "color.npy"))
        return real(scene_dir, *a, **kw)

    monkeypatch.setattr(pipeline_scene, "write_scene", full_at_scene_1)
    out = tmp_path / "data"
    with pytest.raises(FaultError) as err:
        generate_dataset(parse_config(TINY), out, range(3))
    msg = str(err.value)
    assert msg == (f"{out / scene_name(1) / 'color.npy'}: no space left on the device; 1 of 3 scenes complete in "
                   f"{out}; free some space or choose another folder, then re-run the same command to resume")
    assert read_scene_meta(out / scene_name(0)) is not None
    assert not (out / scene_name(1)).exists() and not (out / ".generate.lock").exists()


# ------------------------------------------------------------------------------------------------
# real faults: a full tmpfs, a read-only mount, a folder without write permission


@pytest.mark.slow
def test_disk_full_on_a_small_tmpfs_keeps_complete_scenes_and_resumes_to_the_same_bytes(
        tmpfs, tiny_cfg_file, reference4):
    mnt = tmpfs("1600k")  # room for a scene or two of the tiny config, not four
    out = mnt / "data"
    args = ("generate", "--config", str(tiny_cfg_file), "-n", "4", "--out", str(out))
    line = one_error_line(cli(*args))
    m = re.fullmatch(rf"ERROR (.+): no space left on the device; (\d) of 4 scenes complete in {re.escape(str(out))}; "
                     r"free some space or choose another folder, then re-run the same command to resume", line)
    assert m is not None, line
    assert m.group(1).startswith(str(out))
    complete = {d.name for d in out.glob("scene_*") if read_scene_meta(d) is not None}
    assert len(complete) == int(m.group(2)) < 4
    assert {d.name for d in out.glob("scene_*")} == complete, "half-written scene folders were left behind"
    before = {k: v for k, v in digest(out).items() if k in complete}
    assert before == {k: reference4[k] for k in complete}
    subprocess.run(["mount", "-o", "remount,size=64m", str(mnt)], check=True)
    res = cli(*args)
    assert res.returncode == 0, res.stderr
    assert digest(out) == reference4


@pytest.mark.slow
def test_read_only_file_system_is_one_line(tmpfs, tiny_cfg_file):
    mnt = tmpfs("1m", read_only=True)
    line = one_error_line(cli("generate", "--config", str(tiny_cfg_file), "-n", "1", "--out", str(mnt / "data")))
    assert f"{mnt / 'data'}: read-only file system; 0 of 1 scenes complete" in line
    assert line.endswith("choose a writable folder, then re-run the same command to resume")


def _without_permission_bypass() -> tuple[str, ...]:
    if not LINUX:
        pytest.skip("permission faults are exercised on Linux")
    if os.geteuid() != 0:
        return ()
    if shutil.which("setpriv") is None:
        pytest.skip("running as root (permissions are bypassed) and no setpriv to drop CAP_DAC_OVERRIDE")
    probe = subprocess.run(["setpriv", "--bounding-set=-dac_override,-dac_read_search", "true"], capture_output=True)
    if probe.returncode != 0:
        pytest.skip(f"running as root and setpriv cannot drop CAP_DAC_OVERRIDE: {probe.stderr.decode().strip()}")
    return ("setpriv", "--bounding-set=-dac_override,-dac_read_search")


@pytest.mark.slow
def test_permission_denied_is_one_line(tmp_path, tiny_cfg_file):
    prefix = _without_permission_bypass()
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        line = one_error_line(cli("generate", "--config", str(tiny_cfg_file), "-n", "1", "--out", str(ro),
                                  prefix=prefix))
        assert f"{ro / '.generate.lock'}: permission denied; 0 of 1 scenes complete in {ro}" in line
        scan = tmp_path / "scan.npy"
        np.save(scan, np.random.default_rng(0).uniform(0, 3, (500, 3)).astype(np.float32))
        line = one_error_line(cli("segment", str(scan), "--method", "geometric", "--out", str(ro / "seg"),
                                  prefix=prefix))
        assert line == f"ERROR {ro / 'seg'}: permission denied; check the permissions or choose another folder"
    finally:
        ro.chmod(0o755)


# ------------------------------------------------------------------------------------------------
# bounds


@pytest.mark.parametrize("section, key, value", [
    ("selection", "floor_count", 10**9), ("selection", "wall_count", 10**9), ("selection", "on_top_count", 10**9),
    ("render", "views_per_point", 10**6), ("render", "vantage_points", 10**6), ("render", "width", 10**5),
    ("render", "voxel_size", 1e-9), ("render", "vantage_cell", 1e-9), ("render", "threads", 10**6),
    ("layout", "cell_size", 1e-9), ("layout", "rotations", 10**9), ("layout", "max_nodes", 10**12),
    ("layout", "group_budget_s", 1e12), ("room", "area_max", 1e9), ("room", "height_max", float("inf")),
    ("render", "fx", float("nan")), ("llm", "timeout_s", 1e12), ("llm", "retries", 10**9),
    ("assets", "procedural_count", 10**9), (None, "seed", 10**30), (None, "seed", -5),
])
def test_config_numbers_have_bounds(section, key, value):
    data = {key: value} if section is None else {section: {key: value}}
    with pytest.raises(ConfigError) as err:
        parse_config(data)
    assert key in str(err.value)


def test_every_bounded_config_field_documents_its_bound():
    from assist3d.config import GenerateConfig

    def sections(model):
        for name, f in model.model_fields.items():
            ann = f.annotation
            if isinstance(ann, type) and hasattr(ann, "model_fields"):
                yield from sections(ann)
            else:
                yield name, f

    undocumented = []
    for name, f in sections(GenerateConfig):
        le = [m.le for m in f.metadata if getattr(m, "le", None) is not None]
        if le and name not in ("l_shape_prob", "real_class_prob", "complementary_fraction", "pairing_prob",
                               "temperature") and not name.startswith("tsdf_"):
            desc = (f.description or "").replace(",", "")
            bound = le[0]
            shown = {f"{bound:g}", f"{int(bound)}" if float(bound).is_integer() else "", "2^32-1"}
            if not any(s and s in desc for s in shown):
                undocumented.append(name)
    assert undocumented == []


def test_render_memory_estimate_refuses_before_work_and_passes_the_paper_settings():
    paper = parse_config({})
    assert render_memory_bytes(paper) < 1 * GIB
    check_render_memory(paper, memory=4 * GIB)
    huge = parse_config({"render": {"width": 16384, "height": 16384, "vantage_points": 100, "views_per_point": 360}})
    with pytest.raises(ConfigError) as err:
        check_render_memory(huge, memory=24 * GIB)
    msg = str(err.value)
    assert re.search(r"16384 x 16384 px from 36000 views \(9\.7e\+12 rays\) at 0\.02 m voxels needs about [\d.,]+ GiB "
                     r"of memory \(estimate\)", msg), msg
    assert "24.0 GiB" in msg and "render.width" in msg
    with pytest.raises(ConfigError, match="x 2 workers"):
        check_render_memory(parse_config({"render": {"width": 4000, "height": 3000}}), workers=2, memory=2 * GIB)


def test_generate_refuses_an_infeasible_render_before_any_scene(tmp_path, monkeypatch):
    from assist3d.core import bounds

    monkeypatch.setattr(bounds, "machine_memory_bytes", lambda: 1.0 * GIB)
    cfg = parse_config({**TINY, "render": {**TINY["render"], "width": 8000, "height": 8000}})
    with pytest.raises(ConfigError, match=r"8000 x 8000 px from 12 views .* more than 80% of this machine's 1\.0 GiB"):
        generate_dataset(cfg, tmp_path / "data", range(1))
    assert not (tmp_path / "data").exists()


def test_scene_counts_indices_and_command_line_numbers_are_bounded(tmp_path):
    with pytest.raises(ConfigError, match="at most 1,000,000"):
        check_scene_indices(list(range(MAX_SCENES + 1)))
    with pytest.raises(ConfigError, match="outside 0..999,999,999"):
        check_scene_indices([10**12], what="--only")
    for args, option in ((["generate", "--out", str(tmp_path / "g"), "-n", str(10**12)], "--num-scenes"),
                         (["generate", "--out", str(tmp_path / "g"), "-n", "1", "--workers", str(10**6)], "--workers"),
                         (["bench", "--scenes", str(10**9)], "--scenes"),
                         (["assets", "procedural", "--count", str(10**9)], "--count"),
                         (["model-bench", "--points", str(10**12)], "--points"),
                         (["train", "--config", "x.yaml", "--epochs", str(10**12)], "--epochs"),
                         (["cluster-assets", "--k", "0"], "--k"),
                         (["metrics", "x", "--max-scenes", "-1"], "--max-scenes")):
        res = runner.invoke(app, args)
        assert res.exit_code == 2 and option in res.output, (args, res.output)
    res = runner.invoke(app, ["generate", "--out", str(tmp_path / "g"), "--only", str(10**12)])
    assert isinstance(res.exception, ConfigError) and "--only" in str(res.exception)


def test_engine_voxel_grid_overflow_is_a_data_error_and_training_numbers_are_bounded():
    from assist3d.learn.engine.config import parse_train_config
    from assist3d.learn.engine.voxelize import voxelize

    coord = np.array([[0.0, 0.0, 0.0], [500.0, 0.0, 0.0]], np.float32)
    with pytest.raises(DataError, match="spans .* voxels of 0.01 m"):
        voxelize(coord, np.zeros((2, 3), np.uint8), None, 0.01)
    for section, key, value in (("optim", "batch_size", 10**9), ("data", "voxel_size", 1e-9),
                                ("optim", "epochs", 10**12), ("predict", "top_k", -5)):
        with pytest.raises(ConfigError, match=key):
            parse_train_config({section: {key: value}})


# ------------------------------------------------------------------------------------------------
# inputs that were accepted silently or ended in a traceback


def test_truncated_prediction_npz_is_a_data_error(tmp_path):
    from assist3d.bench.evaluation.predictions import load_predictions, save_predictions

    p = save_predictions(tmp_path / "a.npz", np.ones((2, 10), bool), np.ones(2, np.float32))
    p.write_bytes(p.read_bytes()[:100])
    with pytest.raises(DataError, match=r"a\.npz: cannot read prediction npz"):
        load_predictions(p, 10)


def test_import_that_skips_every_input_fails(tmp_path):
    res = runner.invoke(app, ["assets", "import", "sh3d", str(tmp_path / "none.sh3f"), "--library",
                              str(tmp_path / "lib"), "--workers", "1", "--no-progress"])
    assert res.exit_code != 0 and "nothing imported: all 1 inputs were skipped" in str(res.exception)
    assert "catalog file not found" in res.output


def test_convert_predictions_of_a_missing_folder_fails(tmp_path):
    res = runner.invoke(app, ["convert-predictions", str(tmp_path / "none"), str(tmp_path / "out"), "--to", "txt"])
    assert isinstance(res.exception, DataError) and "prediction folder not found" in str(res.exception)


def test_layout_png_refuses_a_non_finite_pose(tmp_path):
    from assist3d.assets import open_catalog
    from assist3d.scene.layout import build_layout

    cfg = parse_config(TINY)
    cat = open_catalog(None, procedural_count=60)
    data = build_layout(cat, cfg, 3).to_json()
    data["instances"][0]["pose"][0][3] = float("nan")
    p = tmp_path / "layout.json"
    p.write_text(json.dumps(data))
    res = runner.invoke(app, ["layout-png", str(p), "--out", str(tmp_path / "l.png"), "--assets", str(cat.root)])
    assert isinstance(res.exception, DataError) and "non-finite pose" in str(res.exception)
    assert not (tmp_path / "l.png").exists()
