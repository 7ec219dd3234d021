"""Property-based tests: whatever the input, a valid result or the project's own error naming the input.

Arrays of any shape, dtype and values go through the ``array`` reader and the ``segment`` command's
point reader; random overrides go through the configuration loaders. Any exception other than an
:class:`~assist3d.core.errors.AssistError` (or, where documented, pydantic's ``ValidationError``) fails
the test. Settings are small and derandomized so CI runs the same examples in a few seconds.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from pydantic import BaseModel, ValidationError

from assist3d.config import GenerateConfig, load_config, parse_config
from assist3d.data import open_dataset
from assist3d.learn.engine.config import TrainConfig, load_train_config, parse_train_config
from assist3d.core.errors import AssistError, ConfigError
from assist3d.learn.segmenter.config import SegmenterConfig, parse_segmenter_config

SETTINGS = settings(max_examples=80, deadline=None, derandomize=True, database=None, print_blob=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

# ------------------------------------------------------------------------------------ input arrays

#: Values that break naive readers: non-finite, overflowing float32, far out, fractional, negative.
SPECIAL = [np.nan, np.inf, -np.inf, 1e300, -1e39, 1e30, 2.5, -0.5, -1.0, -7.0, 40.0, 1e12, 255.6, 0.0]
DTYPES = ["float32", "float64", "float16", "int64", "int8", "uint16", "bool", "complex128", "object", "str"]


@st.composite
def scan_arrays(draw: st.DrawFn) -> np.ndarray:
    """An (N, K) array, N 0..50, K 0..10: a plausible scan (xyz, rgb, semantic, instance columns)
    with a few cells replaced by special values, then cast to one of :data:`DTYPES`."""
    n = draw(st.integers(0, 50))
    k = draw(st.sampled_from([8, 8, 8, 6, 3, 0, 1, 2, 4, 5, 7, 9, 10]))  # mostly the readers' widths
    rng = np.random.default_rng(draw(st.integers(0, 2**16)))
    base = np.column_stack([rng.uniform(-5, 5, (n, 3)), rng.integers(0, 256, (n, 3)), rng.integers(0, 21, n),
                            rng.integers(-1, 30, n), rng.uniform(-1, 1, (n, 2))])[:, :k]
    if n and k:
        for _ in range(draw(st.integers(0, 3))):
            r, c = draw(st.integers(0, n - 1)), draw(st.integers(0, k - 1))
            base[r, c] = draw(st.sampled_from(SPECIAL))
    dtype = draw(st.sampled_from(DTYPES[:2] * 3 + DTYPES))  # mostly float
    with np.errstate(all="ignore"):
        if dtype == "str":
            return base.astype(str)
        return base.astype(dtype)


def _save(folder: Path, name: str, a: np.ndarray) -> Path:
    path = folder / name
    np.save(path, a, allow_pickle=True)  # object arrays are written as pickles: the reader must refuse them
    return path


def _assert_valid_sample(s: Any, n: int) -> None:
    assert s.coord.dtype == np.float32 and s.coord.shape == (n, 3) and n > 0
    assert np.isfinite(s.coord).all()
    assert s.color.dtype == np.uint8 and s.color.shape == (n, 3)
    for labels in (s.instance, s.segment):
        assert labels.dtype == np.int32 and labels.shape == (n,) and labels.min() >= -1
    assert s.valid.shape == (n,) and s.normal.shape == (n, 3)


@pytest.fixture(scope="module")
def scratch() -> Path:
    with tempfile.TemporaryDirectory(prefix="assist3d-props-") as d:
        yield Path(d)


@SETTINGS
@given(a=scan_arrays())
def test_array_reader_gives_a_valid_sample_or_its_own_error(scratch, a):
    path = _save(scratch, "probe_scan_a.npy", a)
    try:
        sample = open_dataset(f"array:{path}")[0]
    except AssistError as e:
        event(f"refused: {type(e).__name__}")
        assert path.name in str(e), str(e)
    else:
        event("valid sample")
        _assert_valid_sample(sample, len(a))


@SETTINGS
@given(a=scan_arrays())
def test_segment_point_reader_gives_usable_points_or_its_own_error(scratch, a):
    from assist3d.data.scanfile import read_scan
    from assist3d.learn.segmenter.predictor import usable_points

    path = _save(scratch, "probe_scan_b.npy", a)
    try:
        scan = read_scan(path)
        scene_id, coord, color, sample = scan.scene_id, scan.coord, scan.color, scan.sample
        usable = usable_points(str(path), scene_id, coord)
    except AssistError as e:
        event(f"refused: {type(e).__name__}")
        assert path.name in str(e), str(e)
        return
    event("points" if sample is None else "points with labels")
    n = len(a)
    assert scene_id == "probe_scan_b" and coord.dtype == np.float32 and coord.shape == (n, 3) and n > 0
    assert usable.shape == (n,) and usable.any() and np.isfinite(coord[usable]).all()
    assert color is None or (color.dtype == np.uint8 and color.shape == (n, 3))
    if sample is not None:
        _assert_valid_sample(sample, n)


# ------------------------------------------------------------------------------------ configurations

VALUES = st.one_of(
    st.integers(-10**20, 10**20), st.sampled_from([0, -1, 1, 2**31, 10**9]),
    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0.0, -0.0, -1.5, 1e308, float("nan")]),
    st.booleans(), st.none(), st.text(max_size=6), st.sampled_from(["1", "1.5", "nan", "inf", "numpy", "llm"]),
    st.lists(st.integers(-3, 10**6), max_size=4), st.lists(st.floats(allow_nan=True), max_size=3),
    st.dictionaries(st.text(max_size=4), st.integers(), max_size=2),
)


def _fields(model: type[BaseModel]) -> list[tuple[str, ...]]:
    """Dotted paths to every leaf field of a nested pydantic model."""
    out: list[tuple[str, ...]] = []
    for name, f in model.model_fields.items():
        sub = f.annotation
        if isinstance(sub, type) and issubclass(sub, BaseModel):
            out += [(name, *p) for p in _fields(sub)]
        else:
            out.append((name,))
    return out


def overrides_for(model: type[BaseModel]) -> st.SearchStrategy[dict]:
    """Nested dicts setting random fields of ``model`` (and a few unknown keys) to random values."""
    paths = _fields(model) + [("no_such_key",), (next(iter(model.model_fields)), "no_such_field")]

    def build(items: list[tuple[tuple[str, ...], Any]]) -> dict:
        data: dict = {}
        for path, value in items:
            node = data
            for key in path[:-1]:
                if not isinstance(node.get(key), dict):
                    node[key] = {}
                node = node[key]
            node[path[-1]] = value
        return data

    section_as_value = st.tuples(st.sampled_from(list(model.model_fields)).map(lambda k: (k,)), VALUES)
    return st.lists(st.one_of(st.tuples(st.sampled_from(paths), VALUES), section_as_value), max_size=6).map(build)


LOADERS: dict[str, tuple[type[BaseModel], Callable[[dict, str], BaseModel]]] = {
    "generate": (GenerateConfig, lambda d, src: parse_config(d, source=src)),
    "segmenter": (SegmenterConfig, lambda d, src: parse_segmenter_config(d, src)),
    "train": (TrainConfig, lambda d, src: parse_train_config(d, src)),
}


@pytest.mark.parametrize("name", sorted(LOADERS))
def test_config_overrides_validate_or_raise_config_error(name):
    model, parse = LOADERS[name]

    @SETTINGS
    @given(data=overrides_for(model))
    def check(data: dict) -> None:
        try:
            cfg = parse(data, "probe-config.yaml")
        except (ConfigError, ValidationError) as e:
            event(f"refused: {type(e).__name__}")
            assert "probe-config.yaml" in str(e) or isinstance(e, ValidationError), str(e)
        else:
            event("valid")
            assert isinstance(cfg, model)

    check()


@SETTINGS
@given(data=overrides_for(GenerateConfig))
def test_yaml_config_files_load_or_raise_config_error_naming_the_file(scratch, data):
    path = scratch / "probe-generate.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    try:
        cfg = load_config(path)
    except ConfigError as e:
        assert path.name in str(e), str(e)
    else:
        assert isinstance(cfg, GenerateConfig)
    try:
        merged = load_config(None, overrides=data)
    except ConfigError as e:
        assert "<defaults>" in str(e), str(e)
    else:
        assert merged == cfg


@pytest.mark.parametrize("loader", [load_config, load_train_config])
@pytest.mark.parametrize("where", ["top", "nested"])
def test_yaml_python_tags_are_refused_and_run_nothing(tmp_path, loader, where):
    marker = tmp_path / "pwned"
    payload = f'!!python/object/apply:os.system ["touch {marker}"]'
    text = payload if where == "top" else f"render:\n  backend: {payload}\n"
    path = tmp_path / "evil.yaml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError, match=r"evil\.yaml: not valid YAML"):
        loader(path)
    assert not marker.exists()


def test_no_unsafe_yaml_or_pickle_loading_in_the_sources():
    src = Path(__file__).resolve().parents[2] / "src" / "assist3d"
    needles = ("yaml.load(", "yaml.unsafe_load", "yaml.full_load", "Loader=yaml.Loader", "allow_pickle=True",
               "pickle.load")
    hits = [f"{p.relative_to(src)}: {n}" for p in src.rglob("*.py") for n in needles if n in p.read_text()]
    assert not hits, hits
