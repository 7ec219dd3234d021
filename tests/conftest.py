"""Shared fixtures: locations of real data (skipped cleanly when absent), the repository's scripts."""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path
from types import ModuleType
from typing import Callable

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("ASSIST3D_SHARED", ROOT.parent / "shared"))
REAL_SCAN = SHARED / "data" / "real" / "scannet_scene0451_01.npy"
SH3D_DIR = Path("/usr/share/sweethome3d/furniture")
SH3D_JAR = Path("/usr/share/sweethome3d/sweethome3d.jar")


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path_factory, monkeypatch):
    """Never touch the user's cache folder from a test."""
    cache = tmp_path_factory.getbasetemp() / "assist3d-cache"
    monkeypatch.setenv("ASSIST3D_CACHE", str(cache))
    monkeypatch.delenv("ASSIST3D_ASSETS", raising=False)
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)


@pytest.fixture
def real_scan_path() -> Path:
    if not REAL_SCAN.is_file():
        pytest.skip(f"real scan not found at {REAL_SCAN}")
    return REAL_SCAN


@pytest.fixture
def real_dev_dir() -> Path:
    dev = SHARED / "data" / "real" / "dev"
    if not dev.is_dir() or not any(dev.glob("*.npy")):
        pytest.skip(f"real dev scans not found at {dev}")
    return dev


@pytest.fixture
def sh3d_dir() -> Path:
    if not SH3D_DIR.is_dir() or not any(SH3D_DIR.glob("*.sh3f")):
        pytest.skip("Sweet Home 3D furniture catalogs not installed (apt-get install sweethome3d-furniture)")
    return SH3D_DIR


@pytest.fixture
def load_script() -> Callable[[str], ModuleType]:
    """``load_script("name")`` imports ``scripts/name.py`` (a user's tool) or, failing that,
    ``experiments/tools/name.py`` (an experiment's); neither folder is a package."""

    def load(name: str) -> ModuleType:
        path = ROOT / "scripts" / f"{name}.py"
        if not path.is_file():
            path = ROOT / "experiments" / "tools" / f"{name}.py"
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    return load


@pytest.fixture
def one_thread():
    """Torch on one CPU thread for the test: multi-threaded CPU reductions (index_add_, matmul) are not
    bit-reproducible, and a time bound on process CPU time only holds without OpenMP workers spinning
    on busy cores (52 CPU s for a 7 s job once, with another job beside the tests)."""
    torch = pytest.importorskip("torch")
    old = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(old)
