"""Extension points share one registry style: readers, ray casters and planners are looked up by
name, an unknown name is refused with the closest one, and a plugin registered from outside the
package is used by the same entry points as the built-in ones."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.config import parse_config
from assist3d.data import READERS, Reader, open_dataset
from assist3d.data.array import ArrayDataset
from assist3d.core.errors import ConfigError, RenderError
from assist3d.core.registry import Registry
from assist3d.render.raycast import CASTERS, NumpyCaster, make_caster
from assist3d.planning.planners import PLANNERS, make_planner, planner_name
from assist3d.planning.rules import RulePlanner


def test_registry_lookup_suggestions_and_duplicates():
    reg: Registry[int] = Registry("widget")
    reg.add("alpha", 1)

    @reg.register("beta")
    def beta():
        return 2

    assert reg.get("alpha") == 1 and reg.get("beta") is beta and reg.names() == ("alpha", "beta")
    with pytest.raises(ConfigError, match="unknown widget 'alpah'; did you mean 'alpha'"):
        reg.get("alpah")
    with pytest.raises(ConfigError, match="unknown widget 'zzz'; choose one of alpha, beta"):
        reg.get("zzz")
    with pytest.raises(ValueError, match="already registered"):
        reg.add("alpha", 3)
    reg.remove("alpha")
    assert "alpha" not in reg and len(reg) == 1


def test_ray_casters_are_a_registry():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float64)
    f = np.array([[0, 1, 2]], np.int64)
    assert isinstance(make_caster("numpy", v, f), NumpyCaster)
    with pytest.raises(RenderError, match="unknown render backend 'numpi'; did you mean 'numpy'"):
        make_caster("numpi", v, f)
    made = []
    CASTERS.add("test-plugin", lambda vv, ff: made.append(len(ff)) or NumpyCaster(vv, ff))
    try:
        assert isinstance(make_caster("test-plugin", v, f), NumpyCaster) and made == [1]
    finally:
        CASTERS.remove("test-plugin")


def test_a_reader_plugin_opens_through_open_dataset(tmp_path):
    pts = np.zeros((4, 8), np.float32)
    pts[:, :3] = np.arange(12, dtype=np.float32).reshape(4, 3)
    pts[:, 6] = [0, 5, 5, 5]  # semantic: void, then an object class (ScanNet-20 label 5)
    pts[:, 7] = [-1, 0, 0, 1]
    np.save(tmp_path / "s.npy", pts)
    READERS.add("test-plugin", Reader(lambda p, **kw: ArrayDataset(p), frozenset({"flag"})))
    try:
        ds = open_dataset(f"test-plugin:{tmp_path / 's.npy'}?flag=1")
        assert len(ds) == 1 and list(np.unique(ds[0].instance)) == [-1, 0, 1]
        with pytest.raises(ConfigError, match="unknown option"):
            open_dataset(f"test-plugin:{tmp_path / 's.npy'}?other=1")
    finally:
        READERS.remove("test-plugin")
    with pytest.raises(ConfigError, match="unknown format 'test-plugin'"):
        open_dataset(f"test-plugin:{tmp_path / 's.npy'}")


@pytest.mark.parametrize("layout,llm,expected", [
    ({}, {}, "rules"),
    ({"planner": "none"}, {}, "rules"),
    ({"planner": "llm"}, {}, "llm"),
    ({}, {"base_url": "http://127.0.0.1:9/v1", "model": "m"}, "llm"),  # an endpoint switches the default
    ({"planner": "none"}, {"base_url": "http://127.0.0.1:9/v1", "model": "m"}, "rules"),
])
def test_planner_choice(layout, llm, expected):
    cfg = parse_config({"layout": layout, "llm": llm})
    assert planner_name(cfg) == expected and expected in PLANNERS
    if expected == "rules":
        assert isinstance(make_planner(cfg), RulePlanner)


def test_models_are_built_by_name_and_a_new_one_is_one_registration():
    torch = pytest.importorskip("torch")
    from assist3d.learn.engine.config import ModelConfig
    from assist3d.learn.models.mask3d import Mask3D
    from assist3d.learn.zoo import MODELS, build_model
    from assist3d.learn.segmenter.config import NetConfig
    from assist3d.learn.segmenter.model import Segmenter

    assert {"segmenter", "mask3d"} <= set(MODELS.names())
    assert isinstance(build_model("segmenter", NetConfig()), Segmenter)
    small = ModelConfig(enc_channels=(8, 8, 8, 8), dec_channels=(8, 8, 8, 8), enc_blocks=(1, 1, 1, 1),
                        dec_blocks=(1, 1, 1, 1), stem_channels=8, hidden=16, ffn=16, heads=2)
    assert isinstance(build_model("mask3d", small), Mask3D)

    @MODELS.register("test-linear")
    def _linear(width: int) -> torch.nn.Module:
        return torch.nn.Linear(width, 1)

    try:
        assert build_model("test-linear", 3).in_features == 3
    finally:
        MODELS.remove("test-linear")
    with pytest.raises(ConfigError, match="unknown model 'segmentr'; did you mean 'segmenter'"):
        build_model("segmentr", NetConfig())


def test_config_choices_come_from_the_registries(tmp_path):
    """The config takes any planner / ray caster name: one registered from outside the package is chosen
    like a built-in one (no schema edit), and a name nobody registered is refused before anything is
    written, naming the key and the closest registered name."""
    from assist3d.pipeline.dataset import generate_dataset
    from assist3d.pipeline.scene import check_plugins

    made = []
    PLANNERS.add("test-planner", lambda cfg: made.append(cfg.seed) or RulePlanner())
    CASTERS.add("test-caster", lambda v, f: NumpyCaster(v, f))
    try:
        cfg = parse_config({"seed": 5, "layout": {"planner": "test-planner"}, "render": {"backend": "test-caster"}})
        check_plugins(cfg)
        assert isinstance(make_planner(cfg), RulePlanner) and made == [5]
    finally:
        PLANNERS.remove("test-planner")
        CASTERS.remove("test-caster")
    for data, msg in (({"layout": {"planner": "rulez"}}, "layout.planner: unknown relation planner 'rulez'; did you mean 'rules'"),
                      ({"render": {"backend": "embre"}}, "render.backend: unknown render backend 'embre'; did you mean 'embree'")):
        cfg = parse_config(data)
        with pytest.raises(ConfigError, match=msg):
            generate_dataset(cfg, tmp_path / "out", [0])
        assert not (tmp_path / "out").exists()
    with pytest.raises(ConfigError):
        parse_config({"layout": {"planner": ""}})
