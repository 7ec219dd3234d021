"""Chat client details: concurrency slots, endpoint parsing, cache entries, prompt templates."""

from __future__ import annotations

import json
import threading
import time

import pytest

from assist3d.config import LLMConfig
from assist3d.core.errors import ConfigError, LLMError
from assist3d.llm.cache import ResponseCache, cache_key
from assist3d.llm.client import ChatClient, Usage, parse_endpoint
from assist3d.llm.prompts import load_template
from assist3d.llm.schema import parse_json_text
from assist3d.planning.llm_prompts import render_plan_messages
from assist3d.planning.llm_schema import check_answer
from llm_fakeserver import FakeServer, Step
from test_planning_llm_planner import FLOOR, ONTOP, WALL


def _cfg(srv, tmp_path, **kw) -> LLMConfig:
    base = dict(base_url=srv.url, model="m", timeout_s=2.0, retries=0, cache_dir=str(tmp_path / "llm"))
    base.update(kw)
    return LLMConfig(**base)


@pytest.mark.parametrize("limit", [1, 2])
@pytest.mark.slow
def test_concurrency_limit_holds_across_clients(tmp_path, limit):
    """Separate clients (as in separate worker processes) share the lock-file slots."""
    with FakeServer([Step('{"ok": 1}', sleep=0.15)]) as srv:
        clients = [ChatClient(_cfg(srv, tmp_path, concurrency=limit)) for _ in range(4)]
        errors: list[Exception] = []

        def work(k: int) -> None:
            try:
                clients[k].complete([{"role": "user", "content": f"q{k}"}], use_cache=False)
            except Exception as e:  # noqa: BLE001 - surfaced by the assertion below
                errors.append(e)

        threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
        t0 = time.monotonic()
        for t in threads:
            t.start()
        for t in threads:
            t.join(10)
        elapsed = time.monotonic() - t0
    assert not errors and len(srv.requests) == 4
    assert srv.max_active == limit
    assert elapsed >= 0.15 * 4 / limit - 0.03


def test_endpoint_parsing():
    ep = parse_endpoint("https://api.openai.com/v1/")
    assert (ep.scheme, ep.host, ep.port, ep.path) == ("https", "api.openai.com", 443, "/v1/chat/completions")
    assert parse_endpoint("http://localhost:11434/v1/chat/completions").path == "/v1/chat/completions"
    with pytest.raises(ConfigError, match="must not contain credentials"):
        parse_endpoint("https://user:secret@example.com/v1")
    with pytest.raises(ConfigError, match="expected http"):
        parse_endpoint("ftp://example.com")


def test_connection_refused_is_retried_then_fails(tmp_path):
    with FakeServer([Step("x")]) as srv:
        url = srv.url
    cfg = LLMConfig(base_url=url, model="m", timeout_s=1.0, retries=2, backoff_s=0.01, cache_dir=str(tmp_path))
    usage = Usage()
    with pytest.raises(LLMError, match="failed after 3 attempt"):
        ChatClient(cfg).complete([{"role": "user", "content": "hi"}], usage=usage)
    assert usage.calls == 3


def test_cache_key_and_corrupt_entries(tmp_path):
    msgs = [{"role": "user", "content": "hello"}]
    k = cache_key("m", msgs, 0.0)
    assert k == cache_key("m", json.loads(json.dumps(msgs)), 0.0)
    assert len({k, cache_key("m2", msgs, 0.0), cache_key("m", msgs, 0.5),
                cache_key("m", [{"role": "user", "content": "hello!"}], 0.0)}) == 4
    cache = ResponseCache(tmp_path)
    cache.path(k).parent.mkdir(parents=True)
    cache.path(k).write_text("{not json")
    assert cache.get(k) is None  # ignored, then overwritten by a fresh answer
    with FakeServer([Step("fresh")]) as srv:
        ans = ChatClient(_cfg(srv, tmp_path), cache=cache).complete(msgs)
    assert ans.content == "fresh" and cache.get(k).content == "fresh"


def test_non_chat_answer_is_an_error(tmp_path):
    with FakeServer([Step(raw=b'{"foo": 1}')]) as srv:
        with pytest.raises(LLMError, match="not a chat completion"):
            ChatClient(_cfg(srv, tmp_path)).complete([{"role": "user", "content": "x"}])


def test_templates_render_group_vocabulary():
    texts = {r.group: render_plan_messages(r)[-1]["content"] for r in (FLOOR, WALL, ONTOP)}
    assert "- edge (no target)" in texts["floor"] and "- above" not in texts["floor"]
    assert "- height (\"value\": [min_m, max_m])" in texts["wall"] and "- edge" not in texts["wall"]
    assert "- on (\"target\": <placed instance id>)" in texts["on:9"] and "Support (the objects rest on it): id 9" \
        in texts["on:9"]
    for t in texts.values():
        assert "Worked example" in t and "$" not in t
        # the worked example itself is a valid answer shape
        example = t[t.index("Answer:\n") + 8:t.index("\n\nNow answer")]
        data, err = parse_json_text(example)
        assert err is None and isinstance(data["objects"], list)


def test_prompt_dir_overrides_and_errors(tmp_path):
    (tmp_path / "floor.txt").write_text("notes\n### system\nBe brief.\n### user\nPlace $count objects:\n$objects\n")
    msgs = render_plan_messages(FLOOR, tmp_path)
    assert msgs[0] == {"role": "system", "content": "Be brief."}
    assert msgs[1]["content"].startswith("Place 3 objects:\n0: \"Oak dining table\"")
    assert "Worked example" in render_plan_messages(WALL, tmp_path)[-1]["content"]  # built-in wall.txt
    (tmp_path / "floor.txt").write_text("### user\nCosts $5 per $objectz\n")
    with pytest.raises(ConfigError, match="floor.txt"):
        render_plan_messages(FLOOR, tmp_path)
    (tmp_path / "wall.txt").write_text("no sections at all")
    with pytest.raises(ConfigError, match="no '### user' section"):
        load_template("wall", tmp_path)


def test_schema_values_and_fences():
    data, err = parse_json_text('```json\n{"objects": [{"index": 0, "relations": '
                                '[{"relation": "height", "value": [1.0, 9.0]}]}, {"index": 1}]}\n```')
    assert err is None
    checked = check_answer(data, WALL)
    assert checked.order[0].relations == () and any("wall height" in p for p in checked.problems)
    # the painting (0.6 m tall) cannot start 2.5 m up a 2.8 m wall
    tall = check_answer({"objects": [{"index": 0, "relations": [{"relation": "height", "value": [2.5, 2.6]}]},
                                     {"index": 1}]}, WALL)
    assert tall.order[0].relations == () and "at most 2.20 m" in tall.problems[0]
    assert check_answer({"objects": "nope"}, WALL).usable is False
    data, err = parse_json_text('Sure! Here it is: {"objects": []} hope it helps')
    assert err is None and data == {"objects": []}
    assert parse_json_text("{'objects': []}")[1] is not None  # Python literals are not JSON


@pytest.mark.slow
def test_concurrency_limit_holds_across_processes(tmp_path):
    import subprocess
    import sys

    code = ("import sys\nfrom assist3d.config import LLMConfig\nfrom assist3d.llm.client import ChatClient\n"
            "cfg = LLMConfig(base_url=sys.argv[1], model='m', timeout_s=5, retries=0, concurrency=1, "
            "cache_dir=sys.argv[2])\n"
            "ChatClient(cfg).complete([{'role': 'user', 'content': sys.argv[3]}], use_cache=False)\n")
    with FakeServer([Step('{"ok": 1}', sleep=0.6)]) as srv:
        procs = [subprocess.Popen([sys.executable, "-c", code, srv.url, str(tmp_path / "llm"), f"p{k}"])
                 for k in range(3)]
        assert [p.wait(30) for p in procs] == [0, 0, 0]
    assert len(srv.requests) == 3 and srv.max_active == 1
