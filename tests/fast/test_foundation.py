"""Foundation: config validation, atomic writes, seeding, contracts and the catalog round trip."""

from __future__ import annotations

import numpy as np
import pytest

from assist3d.assets.catalog import Catalog
from assist3d.config import load_config, parse_config
from assist3d.core.contracts import AssetRecord, MeshData, PlacedInstance, SceneLayout, Room, SupportSurface
from assist3d.core.errors import AssetError, ConfigError
from assist3d.core.fileio import write_json_atomic
from assist3d.core.rng import make_rng, scene_seed


def test_config_defaults_are_paper_settings():
    cfg = parse_config({})
    assert (cfg.selection.floor_count, cfg.selection.wall_count, cfg.selection.on_top_count) == (100, 50, 5)
    assert cfg.selection.real_class_prob == 0.7
    assert (cfg.render.vantage_points, cfg.render.views_per_point) == (5, 12)
    assert (cfg.render.width, cfg.render.height) == (640, 480)


def test_config_unknown_key_suggests_fix(tmp_path):
    p = tmp_path / "c.yaml"
    p.write_text("selection:\n  flor_count: 3\n")
    with pytest.raises(ConfigError, match="did you mean 'floor_count'"):
        load_config(p)


@pytest.mark.parametrize("schema", ["generate", "train", "segmenter"])
def test_every_config_schema_shares_one_base(schema):
    """Generation, training and segmenter configs behave alike: a misspelt key names the closest
    known one, NaN is refused, and an assignment is validated (not only the file)."""
    from pydantic import ValidationError

    from assist3d.config import Section
    from assist3d.learn.engine.config import parse_train_config
    from assist3d.learn.segmenter.config import parse_segmenter_config

    parse, typo, fix, nan = {
        "generate": (parse_config, {"selection": {"flor_count": 3}}, "floor_count", {"room": {"height_min": float("nan")}}),
        "train": (parse_train_config, {"optim": {"batch_sise": 2}}, "batch_size", {"optim": {"lr": float("nan")}}),
        "segmenter": (parse_segmenter_config, {"optim": {"batch_sise": 2}}, "batch_size",
                      {"optim": {"lr": float("nan")}}),
    }[schema]
    with pytest.raises(ConfigError, match=f"did you mean '{fix}'"):
        parse(typo, source="x.yaml")
    with pytest.raises(ConfigError, match="x.yaml: invalid .*\\n  .*finite"):
        parse(nan, source="x.yaml")
    cfg = parse({})
    assert isinstance(cfg, Section)
    section = next(v for v in vars(cfg).values() if isinstance(v, Section))
    name, value = next((k, v) for k, v in vars(section).items() if isinstance(v, (int, float)) and not isinstance(v, bool))
    with pytest.raises(ValidationError):
        setattr(section, name, "not a number")


def test_config_bad_yaml_names_file(tmp_path):
    p = tmp_path / "c.yaml"
    p.write_text("selection: [\n")
    with pytest.raises(ConfigError, match=str(p)):
        load_config(p)


def test_seeds_are_stable_and_distinct():
    assert scene_seed(0, 3) == scene_seed(0, 3)
    assert len({scene_seed(0, k) for k in range(100)}) == 100
    a = make_rng(5, "layout").random(4)
    b = make_rng(5, "render").random(4)
    assert not np.allclose(a, b)
    np.testing.assert_array_equal(a, make_rng(5, "layout").random(4))


def test_atomic_write_leaves_old_file_on_failure(tmp_path):
    p = tmp_path / "x.json"
    write_json_atomic(p, {"a": 1})

    class Boom:
        pass

    with pytest.raises(TypeError):
        write_json_atomic(p, {"a": Boom()})
    assert p.read_text().strip().replace(" ", "").replace("\n", "") == '{"a":1}'
    assert [f.name for f in tmp_path.iterdir()] == ["x.json"]


def _cube_mesh() -> MeshData:
    import trimesh

    m = trimesh.creation.box((1.0, 0.5, 0.8))
    m.apply_translation((0, 0, 0.4))
    return MeshData(m.vertices.astype(np.float32), m.faces.astype(np.int32),
                    np.full((len(m.faces), 3), 200, np.uint8))


def test_catalog_round_trip_and_idempotent(tmp_path):
    cat = Catalog.open_or_create(tmp_path / "lib")
    rec = AssetRecord(id="test:box", source="test", name="box", class_name="box", groups=("floor",),
                      size=(1.0, 0.5, 0.8), supports=(SupportSurface(0.8, ((-0.5, -0.25), (0.5, -0.25), (0.5, 0.25), (-0.5, 0.25))),))
    cat.add(rec, _cube_mesh())
    cat.add(rec, _cube_mesh())
    cat.save()
    again = Catalog.open(tmp_path / "lib")
    assert len(again) == 1
    r = again.get("test:box")
    assert r.triangles == 12 and r.supports[0].height == pytest.approx(0.8)
    mesh = again.load_mesh(r)
    assert mesh.vertices.dtype == np.float32 and not mesh.vertices.flags.writeable
    st = again.stats().to_json()
    assert st["assets"] == 1 and st["groups"] == {"floor": 1, "wall": 0, "obj": 0}


def test_catalog_missing_is_clear(tmp_path):
    with pytest.raises(AssetError, match="index.json missing"):
        Catalog.open(tmp_path)


def test_layout_json_round_trip():
    inst = PlacedInstance(1, "a", "chair", "floor", np.eye(4))
    lay = SceneLayout(Room(((0, 0), (4, 0), (4, 3), (0, 3)), 2.8), (inst,), (), seed=1, seconds=0.1)
    back = SceneLayout.from_json(lay.to_json())
    assert back.to_json() == lay.to_json()
    with pytest.raises(ValueError):
        inst.pose[0, 0] = 2.0


def test_help_texts_keep_their_bracketed_words():
    """The CLI's help goes through rich markup, which silently drops an unescaped "[view]" or "[ray]" (an
    extra's name) as if it were a style tag: every such bracket in a help text must be escaped."""
    import re

    import click
    import typer

    from assist3d.cli import app

    tag = re.compile(r"(?<!\\)\[[a-z#/@][^\[\]]*\]")
    bad = []

    def walk(cmd: click.Command, name: str) -> None:
        texts = [cmd.help or "", *(getattr(p, "help", None) or "" for p in cmd.params)]
        bad.extend(f"{name}: {m}" for t in texts for m in tag.findall(t))
        for sub_name, sub in getattr(cmd, "commands", {}).items():
            walk(sub, f"{name} {sub_name}")

    walk(typer.main.get_command(app), "assist3d")
    assert not bad, bad
