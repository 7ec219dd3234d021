"""The package's import structure (docs/architecture.md, "Imports"): no import cycle between modules
(importing ``a.b.c`` also runs the ``__init__`` of ``a.b``) nor between the top-level folders, an
import inside a function only where the rule allows one (an optional extra, a documented heavy
module, or, in ``assist3d.cli`` only, the stage module a command runs), and the layering: ``core``
imports nothing else of the package; generation never imports the learning side (``learn``) or the
benchmarking side (``bench``)."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src"
PKG = SRC / "assist3d"

#: optional extras: importing them at module level would break a core install
EXTRAS = {"torch", "ray", "spconv", "httpx", "skimage"}
#: heavy third-party modules (0.3-2.5 s to import on the 2-core VM), loaded by the functions that use them
HEAVY = {"trimesh", "shapely", "scipy.sparse", "scipy.spatial", "PIL", "embreex", "matplotlib",
         "mapbox_earcut"}
#: package modules that are loaded on first use: the procedural library builders (they pull in
#: trimesh and shapely; only needed when the library is first built) and the LLM planner (only when
#: an endpoint is configured)
LAZY_INTERNAL = {"assist3d.assets.procedural", "assist3d.planning.llm_planner"}
#: light modules every command needs: a CLI command imports them at module level like anyone else
CORE = {"assist3d.core", "assist3d.config"}
#: the generation stages: they never import the learning or the benchmarking side
GENERATION = {"assist3d.core", "assist3d.config", "assist3d.assets", "assist3d.scene", "assist3d.planning",
              "assist3d.placement", "assist3d.render", "assist3d.export", "assist3d.pipeline", "assist3d.llm"}


def _modules() -> dict[str, Path]:
    out = {}
    for p in PKG.rglob("*.py"):
        parts = list(p.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


MODULES = _modules()


def _targets(module: str, path: Path, node: ast.Import | ast.ImportFrom) -> list[str]:
    """The modules an import statement loads (``from pkg import sub`` names ``pkg.sub``)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    base = node.module or ""
    if node.level:
        pkg = module if path.name == "__init__.py" else module.rsplit(".", 1)[0]
        for _ in range(node.level - 1):
            pkg = pkg.rsplit(".", 1)[0]
        base = f"{pkg}.{base}" if base else pkg
    return [f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base for a in node.names]


def _with_parents(target: str) -> set[str]:
    """``a.b.c`` and the packages whose ``__init__`` importing it runs first (``a.b``; the root aside)."""
    parts = target.split(".")
    return {".".join(parts[:n]) for n in range(2, len(parts) + 1)}


def _imports() -> tuple[dict[str, set[str]], list[tuple[str, str, int]]]:
    """Module-level edges inside the package, and every (module, target, line) imported in a function."""
    graph: dict[str, set[str]] = {m: set() for m in MODULES}
    local: list[tuple[str, str, int]] = []
    for mod, path in MODULES.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        in_func: set[int] = set()
        for fn in ast.walk(tree):
            if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for node in ast.walk(fn):
                    if isinstance(node, (ast.Import, ast.ImportFrom)) and id(node) not in in_func:
                        in_func.add(id(node))
                        local += [(mod, t, node.lineno) for t in _targets(mod, path, node)]
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)) and id(node) not in in_func:
                graph[mod] |= {p for t in _targets(mod, path, node) for p in _with_parents(t)
                               if p in MODULES and p != mod and not mod.startswith(p + ".")}
    return graph, local


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 10 * len(graph)))
    try:
        for v in graph:
            if v not in index:
                visit(v)
    finally:
        sys.setrecursionlimit(limit)
    return out


def _allowed(module: str, target: str) -> bool:
    def under(names: set[str]) -> bool:
        return any(target == n or target.startswith(n + ".") for n in names)

    if under(EXTRAS) or under(HEAVY) or under(LAZY_INTERNAL):
        return True
    if module == "assist3d.cli" or module.startswith("assist3d.cli."):
        # a command imports the stage it runs when it runs, so `assist3d --help` loads none of them
        return target.startswith("assist3d.") and not under(CORE)
    return False


@pytest.mark.slow
def test_no_import_cycle():
    graph, _ = _imports()
    assert _cycles(graph) == []


def _folders(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    """The module-level graph between the package's top-level folders (``assist3d.scene``,
    ``assist3d.placement``, ...): an edge wherever a module of one imports a module of another."""
    def top(m: str) -> str:
        return ".".join(m.split(".")[:2])
    out: dict[str, set[str]] = {top(m): set() for m in graph}
    for m, ts in graph.items():
        out[top(m)] |= {top(t) for t in ts if top(t) != top(m)}
    return out


@pytest.mark.slow
def test_no_import_cycle_between_folders():
    """Folders stack: none imports, at module level, a folder that imports it back (docs/architecture.md,
    "Restructure history"; scene/ and placement/ did while their shared geometry lived in scene/)."""
    graph, _ = _imports()
    assert _cycles(_folders(graph)) == []


def test_folder_graph_joins_modules_of_one_folder():
    graph = {"assist3d.scene.layout": {"assist3d.placement"}, "assist3d.placement": {"assist3d.scene.geometry"},
             "assist3d.scene.geometry": set(), "assist3d.scene": set()}
    assert _cycles(_folders(graph)) == [["assist3d.placement", "assist3d.scene"]]


def _with_local(graph: dict[str, set[str]], local: list[tuple[str, str, int]]) -> dict[str, set[str]]:
    """The module-level graph plus an edge for every import inside a function (to the package
    modules it loads, parents included, as :func:`_imports` adds module-level edges)."""
    out = {m: set(ts) for m, ts in graph.items()}
    for mod, target, _ in local:
        out.setdefault(mod, set()).update(p for p in _with_parents(target)
                                          if p in MODULES and p != mod and not mod.startswith(p + "."))
    return out


@pytest.mark.slow
def test_no_import_cycle_between_folders_with_function_imports():
    """A lazy import inside a function does not hide a circle between folders: counting those imports
    too, no folder imports a folder that imports it back (llm/ and planning/ did while the LLM
    planner lived in llm/ and planning/planners.py imported it on first use)."""
    graph, local = _imports()
    assert _cycles(_folders(_with_local(graph, local))) == []
    # the check can fail: a function-local import closing a circle between two folders is found
    modules = {"assist3d.planning.relations": set(), "assist3d.planning.planners": set(), "assist3d.planning": set(),
               "assist3d.llm.prompts": {"assist3d.planning.relations"}, "assist3d.llm": set()}
    lazy = [("assist3d.planning.planners", "assist3d.llm.prompts", 1)]
    assert _cycles(_folders(modules)) == []
    assert _cycles(_folders(_with_local(modules, lazy))) == [["assist3d.llm", "assist3d.planning"]]


@pytest.mark.slow
def test_imports_inside_functions_follow_the_rule():
    _, local = _imports()
    bad = [f"{m}:{line} imports {t}" for m, t, line in local if not _allowed(m, t)]
    assert bad == [], "move these imports to the top of the module (or document why they are lazy):\n" + "\n".join(bad)


def _under(module: str, names: set[str]) -> bool:
    return any(module == n or module.startswith(n + ".") for n in names)


@pytest.mark.slow
def test_layering():
    """core/ needs nothing else of the package; no generation module reaches learn/ or bench/,
    at module level or inside a function."""
    graph, local = _imports()
    edges = {(m, t) for m, ts in graph.items() for t in ts} | {(m, t) for m, t, _ in local if t in MODULES}
    core_out = sorted(f"{m} -> {t}" for m, t in edges
                      if _under(m, {"assist3d.core"}) and not _under(t, {"assist3d.core"}))
    assert core_out == []
    gen_to_learn = sorted(f"{m} -> {t}" for m, t in edges
                          if _under(m, GENERATION) and _under(t, {"assist3d.learn", "assist3d.bench"}))
    assert gen_to_learn == []


def test_parent_packages_count_as_imported():
    """The cycle a ``from ..pipeline.records import`` would make (export -> pipeline/__init__ ->
    export) is only visible with the parent package's ``__init__`` as an edge."""
    assert _with_parents("assist3d.pipeline.ray_backend") == {"assist3d.pipeline", "assist3d.pipeline.ray_backend"}


def test_cycle_finder_finds_a_cycle():
    """The checker itself: a two-module loop and a three-module loop are reported, a chain is not."""
    graph = {"a": {"b"}, "b": {"a"}, "c": {"d"}, "d": {"e"}, "e": {"c"}, "f": {"a"}}
    assert sorted(_cycles(graph)) == [["a", "b"], ["c", "d", "e"]]
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": set()}) == []


@pytest.mark.parametrize("module,target,ok", [
    ("assist3d.pipeline", "torch", True),
    ("assist3d.pipeline", "assist3d.render", False),
    ("assist3d.pipeline", "json", False),
    ("assist3d.cli.generate", "assist3d.pipeline", True),
    ("assist3d.cli.generate", "assist3d.core.fileio", False),
    ("assist3d.cli.generate", "time", False),
    ("assist3d.assets", "assist3d.assets.procedural", True),
])
def test_rule(module, target, ok):
    assert _allowed(module, target) is ok
