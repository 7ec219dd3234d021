"""``scripts/fuzz_files.py``, the seeded mutation fuzzer over real files of every input kind: a small
slice here, the full 1,000 cases in the slow tier (docs/reliability.md, "Damaged files")."""

from __future__ import annotations

import os
from collections import Counter

import pytest


@pytest.fixture(scope="module")
def fuzz(tmp_path_factory):
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "scripts" / "fuzz_files.py"
    spec = importlib.util.spec_from_file_location("fuzz_files", path)
    module = importlib.util.module_from_spec(spec)
    import sys

    sys.modules.setdefault("fuzz_files", module)  # its dataclasses look their module up
    spec.loader.exec_module(module)
    examples = tmp_path_factory.mktemp("fuzz") / "examples"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("ASSIST3D_CACHE", str(tmp_path_factory.getbasetemp() / "assist3d-cache"))
        mp.setenv("OMP_NUM_THREADS", "1")
        import subprocess
        import sys

        env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in (str(path.parents[1] / "src"),
                                                                         os.environ.get("PYTHONPATH", "")) if p)}
        subprocess.run([sys.executable, str(path), "--build", str(examples)], check=True, env=env)
    return module, examples


def _not_clear(outcomes) -> list[str]:
    return [f"case {o.index} {o.target} {o.operator} ({o.what}): {o.cls}: {o.note}" for o in outcomes
            if o.cls != "clear"]


@pytest.mark.slow  # its fixture builds the examples in a subprocess
def test_the_same_seed_gives_the_same_cases(fuzz, tmp_path):
    module, examples = fuzz
    ts = module.targets(examples)
    data = (examples / "config" / "generate.yaml").read_bytes()
    import random

    for op in module.OPERATORS:
        a = module.MUTATE[op](data, "yaml", random.Random("7:3"))
        b = module.MUTATE[op](data, "yaml", random.Random("7:3"))
        assert a == b, op
    kinds = {t.kind for t in ts}
    assert kinds == {"config", "catalog", "mesh manifest", "mesh", "scan", "scannet scene", "predictions", "checkpoint",
                     "dataset"}
    assert {t.fmt for t in ts if t.kind == "mesh"} == {"obj", "glb", "gltf", "ply", "stl", "off"}
    plans = module.plan(ts, 2 * len(ts) * len(module.OPERATORS), 0)
    assert {(p.target.name, p.operator) for p in plans} == {(t.name, op) for t in ts for op in module.OPERATORS}


@pytest.mark.slow  # its fixture builds the examples in a subprocess
def test_a_seeded_slice_of_damaged_files_ends_clear(fuzz):
    """One case of every target (the operators taking turns, seed 1) and the families of issue 54 (a
    config in Latin-1, a config nested 5,000 levels, a manifest.json nested 100,000 levels): every
    outcome clear."""
    module, examples = fuzz
    outcomes = module.fuzz(0, 1, examples=examples, timeout=60.0, one_each=True)
    n = len(module.targets(examples))
    assert len(outcomes) == n + len(module.FAMILIES)
    assert {o.operator for o in outcomes} == set(module.OPERATORS)
    assert not _not_clear(outcomes), "\n".join(_not_clear(outcomes))
    latin, deep, manifest = outcomes[-3:]
    assert "re-encoded as latin-1" in latin.what and "not UTF-8 text" in latin.note
    assert "5000" in deep.what and "nested too deeply" in deep.note
    assert manifest.target == "dataset:manifest.json" and "100000" in manifest.what
    assert "manifest.json: unreadable manifest (nested too deeply" in manifest.note


@pytest.mark.slow
def test_a_thousand_damaged_files_end_clear(fuzz):
    """The campaign of docs/reliability.md: 1,000 seeded cases (seed 0) and the families, 0 traceback /
    silent / unclear / hang / loss."""
    module, examples = fuzz
    outcomes = module.fuzz(1000, 0, examples=examples, timeout=60.0)
    assert len(outcomes) == 1000 + len(module.FAMILIES)
    counts = Counter(o.cls for o in outcomes)
    assert counts["clear"] == len(outcomes), ("\n".join(_not_clear(outcomes)), counts)
    assert {o.kind for o in outcomes} >= {"config", "catalog", "mesh", "scan", "predictions", "checkpoint", "dataset"}
