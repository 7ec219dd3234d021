"""VLM layout score: rendered views, the scoring request, repair, cache, failures."""

from __future__ import annotations

import base64
import io
import json
import logging
import os
import time

import numpy as np
import pytest

from assist3d.config import LLMConfig
from assist3d.core.contracts import SceneMesh
from assist3d.core.errors import DataError
from assist3d.bench.metrics.views import encode_png, render_point_views, render_views
from assist3d.bench.metrics.vlm import score_layout, vlm_layout_score
from llm_fakeserver import SENTINEL, FakeServer, Step, files_containing


def decode_png(data: bytes) -> np.ndarray:
    """Decode a PNG written by encode_png: an 8-bit RGB image with no metadata chunks."""
    from PIL import Image

    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    img = Image.open(io.BytesIO(data))
    assert img.mode == "RGB" and not img.info.keys() - {"dpi"}, img.info  # no timestamps or text chunks
    return np.asarray(img)


def test_png_round_trip():
    img = (np.arange(5 * 7 * 3) % 251).astype(np.uint8).reshape(5, 7, 3)
    assert np.array_equal(decode_png(encode_png(img)), img)


def _box(lo, hi):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], np.float32)
    f = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]], np.int32)
    return v, f


def _scene() -> SceneMesh:
    fv = np.array([[0, 0, 0], [4, 0, 0], [4, 3, 0], [0, 3, 0]], np.float32)
    ff = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
    bv, bf = _box((1.5, 1.0, 0.0), (2.5, 2.0, 0.8))
    verts = np.concatenate([fv, bv])
    faces = np.concatenate([ff, bf + len(fv)])
    colors = np.concatenate([np.full((2, 3), 120, np.uint8), np.tile(np.array([[200, 30, 30]], np.uint8), (12, 1))])
    inst = np.array([-1, -1] + [1] * 12, np.int32)
    part = np.array([-1, -1] + [1] * 12, np.int32)
    return SceneMesh(verts, faces, colors, inst, np.where(inst > 0, 0, -1).astype(np.int32), part, ("floor",))


def test_render_views_shows_the_object():
    scene = _scene()
    views = render_views(scene, n=3, size=64)
    assert len(views) == 3 and views == render_views(scene, n=3, size=64)  # deterministic bytes
    for png in views:
        img = decode_png(png).astype(int)
        assert img.shape == (64, 64, 3)
        red = (img[..., 0] > 2 * img[..., 1] + 20)
        assert red.sum() > 30  # the red box is in view from every corner
        grey = (np.abs(img[..., 0] - img[..., 1]) < 3) & (img[..., 0] < 200)
        assert grey.sum() > 100  # and so is the floor


def test_render_point_views_nearest_point_wins():
    rng = np.random.default_rng(0)
    floor = np.column_stack([rng.uniform(0, 4, 20000), rng.uniform(0, 3, 20000), np.zeros(20000)])
    box = np.column_stack([rng.uniform(1.5, 2.5, 5000), rng.uniform(1.0, 2.0, 5000), np.full(5000, 0.8)])
    coord = np.concatenate([floor, box]).astype(np.float32)
    color = np.concatenate([np.full((20000, 3), 90), np.tile([[20, 200, 20]], (5000, 1))]).astype(np.uint8)
    views = render_point_views(coord, color, n=4, size=96)
    assert len(views) == 4
    img = decode_png(views[0]).astype(int)
    green = img[..., 1] > img[..., 0] + 60
    assert green.sum() > 100
    # the box top hides the floor below it: its silhouette is solid green, no grey floor shows through
    ys, xs = np.nonzero(green)
    assert green[ys.min() + 3:ys.max() - 2, xs.min() + 6:xs.max() - 5].mean() > 0.9
    grey = (img[..., 0] == img[..., 1]) & (img[..., 0] < 100)
    assert grey.sum() > 1000  # the floor fills much of the view


GOOD = json.dumps({"score": 72, "reason": "Furniture against walls, free floor space."})


@pytest.fixture
def secret_env(monkeypatch, tmp_path, caplog):
    monkeypatch.setenv("OPENAI_API_KEY", SENTINEL)
    caplog.set_level(logging.DEBUG)
    yield
    assert SENTINEL not in caplog.text
    assert not files_containing(SENTINEL, tmp_path, os.environ["ASSIST3D_CACHE"])


def _cfg(srv: FakeServer, tmp_path, **kw) -> LLMConfig:
    base = dict(base_url=srv.url, model="text-model", vlm_model="vision-model", timeout_s=1.0, retries=0,
                backoff_s=0.01, cache_dir=str(tmp_path / "llm"))
    base.update(kw)
    return LLMConfig(**base)


IMAGES = [encode_png(np.full((8, 8, 3), k, np.uint8)) for k in (10, 200)]


def test_score_request_and_cache(secret_env, tmp_path):
    with FakeServer([Step(GOOD)]) as srv:
        score, details = score_layout(IMAGES, _cfg(srv, tmp_path))
    assert score == 72.0 and details["model"] == "vision-model" and details["llm_calls"] == 1
    assert "Furniture" in details["reason"] and not details["cached"]
    body = srv.requests[0]["json"]
    assert body["model"] == "vision-model"
    parts = body["messages"][-1]["content"]
    assert "from 0 to 100" in parts[0]["text"]
    urls = [p["image_url"]["url"] for p in parts[1:]]
    assert [base64.b64decode(u.split(",", 1)[1]) for u in urls] == IMAGES
    with FakeServer([Step(status=500)]) as srv2:
        again, details2 = score_layout(IMAGES, _cfg(srv2, tmp_path))
    assert again == 72.0 and details2["cached"] and len(srv2.requests) == 0


def test_bad_score_gets_one_repair(secret_env, tmp_path):
    with FakeServer([Step('{"score": 150}'), Step('{"score": "64", "reason": "ok"}')]) as srv:
        score, details = score_layout(IMAGES, _cfg(srv, tmp_path))
    assert score == 64.0 and details["repairs"] == 1
    assert "outside 0-100" in srv.requests[1]["json"]["messages"][-1]["content"]
    with FakeServer([Step("great layout!")]) as srv:
        score, details = score_layout(IMAGES[:1], _cfg(srv, tmp_path))
    assert score is None and len(srv.requests) == 2 and "repair" in details["error"]


@pytest.mark.slow
def test_stall_gives_none_within_timeout(secret_env, tmp_path):
    with FakeServer([Step(GOOD, sleep=20)]) as srv:
        t0 = time.monotonic()
        score, details = score_layout(IMAGES, _cfg(srv, tmp_path, retries=2))
    assert score is None and time.monotonic() - t0 < 1.5 and "timeout_s" in details["error"]


def test_vlm_layout_score_of_a_scene_folder(secret_env, tmp_path):
    scene = tmp_path / "scene_0000"
    scene.mkdir()
    rng = np.random.default_rng(1)
    np.save(scene / "coord.npy", rng.uniform(0, 3, (3000, 3)).astype(np.float32))
    np.save(scene / "color.npy", rng.integers(0, 255, (3000, 3)).astype(np.uint8))
    assert vlm_layout_score(scene, LLMConfig()) is None  # no endpoint: no score, no error
    with FakeServer([Step(GOOD)]) as srv:
        assert vlm_layout_score(scene, _cfg(srv, tmp_path), n_views=2, size=32) == 72.0
    assert len([p for p in srv.requests[0]["json"]["messages"][-1]["content"] if p["type"] == "image_url"]) == 2
    from assist3d.core.contracts import Room

    room = Room(((0.0, 0.0), (4.0, 0.0), (4.0, 3.0), (0.0, 3.0)), 2.6)
    (scene / "layout.json").write_text(json.dumps({"room": room.to_json()}))
    with FakeServer([Step(GOOD)]) as srv:
        vlm_layout_score(scene, _cfg(srv, tmp_path), n_views=2, size=32)  # new prompt text: not a cache hit
    assert "It is a rectangular room, 4.0 x 3.0 m" in srv.requests[0]["json"]["messages"][-1]["content"][0]["text"]
    (scene / "color.npy").write_bytes(b"garbage")
    with pytest.raises(DataError, match="color.npy"):
        vlm_layout_score(scene, _cfg(srv, tmp_path))


def test_cameras_stay_inside_an_l_shaped_room():
    from shapely.geometry import Point, Polygon

    from assist3d.bench.metrics.views import camera_positions

    poly = Polygon([(0, 0), (6, 0), (6, 4), (3, 4), (3, 6), (0, 6)])
    inside = lambda xy: np.array([poly.contains(Point(*p)) for p in xy])  # noqa: E731
    eyes, target = camera_positions(np.array([0.0, 0.0]), np.array([6.0, 6.0]), 0.0, 2.7, 6, inside)
    assert all(poly.contains(Point(*e[:2])) for e in eyes)
    assert np.allclose(eyes[:, 2], 0.85 * 2.7) and np.allclose(target, [3.0, 3.0, 0.54])
    # the notch corner (6, 6) moved in; the free corner (0, 0) kept its 12 % inset
    assert np.allclose(eyes[0, :2], [0.36, 0.36]) and eyes[1, 0] <= 4.5 and poly.contains(Point(*eyes[1, :2]))
