"""Wall time of one scene's LLM relation planning against a local endpoint of fixed latency.

Starts a chat-completions server on 127.0.0.1 that answers every planning prompt with a
well-formed plan after ``--latency`` seconds (plus ``--token-s`` per answer token, since a real
model's answer time grows with its length) (and, with ``--stall-every K``, stalls ``--stall-s``
seconds on every K-th request it receives: the hostile endpoint of issue 14), then builds
the same layout (preset assist3d, paper selection counts) with the groups planned one after
another ("serial"), with the on-top groups planned concurrently ("concurrent") and, with
``--modes ...,batched``, concurrently in prompts of ``--on-top-batch`` groups ("batched"), each with
a fresh answer cache, and checks that the layouts are identical; ``--answer-formats full,compact``
runs every mode with each ``llm.answer_format`` (the endpoint answers the same relations in the form
the prompt asks for).

    python scripts/bench_llm_planning.py --assets LIBRARY [--seed 3] [--latency 2] [--concurrency 8]
        [--token-s 0.02] [--stall-every 6 --stall-s 45 --scene-budget 120] [--modes serial,concurrent,batched
        --on-top-batch 8] [--answer-formats full,compact] [--json]

No network access: the server is local and the key is a dummy. Figures go in docs/llm.md.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

from assist3d.assets import open_catalog_for
from assist3d.config.presets import compose
from assist3d.scene.layout import build_layout

COUNT = re.compile(r"to (?:arrange|put on it|hang) \((\d+)\)")
SUPPORT = re.compile(r"Support \(the objects rest on it\): id (\d+)")
BATCH_GROUP = re.compile(r'Group "(on:\d+)", support id (\d+):[^\n]*\nObjects of on:\d+ \((\d+)\)')


def _entry(i: int, rels: list[dict], compact: bool):
    """One object of an answer, in the full or the compact form (the same content)."""
    if not compact:
        return {"index": i, "relations": rels}
    return [i, *(r["relation"] if len(r) == 1 else [r["relation"], *(r["value"] if "value" in r else [r["target"]])]
                 for r in rels)]


def plan_answer(prompt: str) -> str:
    """A well-formed plan for the group (or, for a batch prompt, each group) the prompt asks
    about: every object listed once, the same plan for a group whether asked alone or in a batch,
    in the answer form the prompt asks for (the compact prompts say "as one list")."""
    compact = "as one list" in prompt
    if "Groups to dress" in prompt:
        return json.dumps({"groups": [
            {"group": g, "objects": [_entry(i, [{"relation": "on", "target": int(sid)}], compact)
                                     for i in range(int(n))]} for g, sid, n in BATCH_GROUP.findall(prompt)]})
    n = int(COUNT.search(prompt).group(1))
    sup = SUPPORT.search(prompt)
    if sup:
        rels = [[{"relation": "on", "target": int(sup.group(1))}] for _ in range(n)]
    elif "Wall objects to hang" in prompt:
        rels = [[{"relation": "height", "value": [1.0, 1.8]}] for _ in range(n)]
    else:
        rels = [[{"relation": "edge"}] + ([{"relation": "near", "target": i - 1}] if i else []) for i in range(n)]
    return json.dumps({"objects": [_entry(i, r, compact) for i, r in enumerate(rels)]})


class LatencyServer:
    """A threaded fake endpoint: fixed latency per answer, optional deterministic stalls."""

    def __init__(self, latency: float, stall_every: int, stall_s: float, token_s: float = 0.0) -> None:
        self.requests = 0
        self.stalls = 0
        self.max_active = 0
        self._active = 0
        self._lock = threading.Lock()
        owner = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args) -> None:
                pass

            def do_POST(self) -> None:
                body = json.loads(self.rfile.read(int(self.headers.get("Content-Length", 0))))
                prompt = body["messages"][-1]["content"]
                with owner._lock:
                    owner.requests += 1
                    stall = stall_every > 0 and owner.requests % stall_every == 0
                    owner.stalls += int(stall)
                    owner._active += 1
                    owner.max_active = max(owner.max_active, owner._active)
                try:
                    content = plan_answer(prompt)
                    # a real model's answer time grows with its length: token_s per answer token (~4 chars)
                    time.sleep(stall_s if stall else latency + token_s * (len(content) // 4))
                    out = json.dumps({"id": "bench", "object": "chat.completion", "model": body.get("model"),
                                      "choices": [{"index": 0, "finish_reason": "stop",
                                                   "message": {"role": "assistant", "content": content}}],
                                      "usage": {"prompt_tokens": len(prompt) // 4,
                                                "completion_tokens": len(content) // 4}}).encode()
                    self.send_response(200)
                    self.send_header("Content-Type", "application/json")
                    self.send_header("Content-Length", str(len(out)))
                    self.end_headers()
                    self.wfile.write(out)
                except (BrokenPipeError, ConnectionResetError):
                    pass
                finally:
                    with owner._lock:
                        owner._active -= 1

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.httpd.daemon_threads = True
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}/v1"
        threading.Thread(target=self.httpd.serve_forever, daemon=True).start()

    def close(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()


def run_once(args, mode: str, cache_dir: str, answer_format: str = "full") -> dict:
    server = LatencyServer(args.latency, args.stall_every, args.stall_s, args.token_s)
    try:
        llm = {"base_url": server.url, "model": "bench-fake", "cache_dir": cache_dir, "retries": 0,
               "answer_format": answer_format,
               "timeout_s": args.timeout, "concurrency": args.concurrency, "plan_concurrently": mode != "serial",
               "on_top_batch": args.on_top_batch if mode == "batched" else 1, "max_failures": 1000}
        if args.scene_budget:
            llm["scene_budget_s"] = args.scene_budget
        cfg = compose(preset="assist3d", overrides={"assets": {"library": args.assets}, "layout": {"planner": "llm"},
                                                     "llm": llm})
        catalog = open_catalog_for(cfg.assets)
        t0 = time.perf_counter()
        layout = build_layout(catalog, cfg, args.seed)
        seconds = time.perf_counter() - t0
    finally:
        server.close()
    groups = layout.planner
    return {"mode": mode if answer_format == "full" else f"{mode}/{answer_format}", "seconds": round(seconds, 2),
            "groups": len(groups), "llm_groups": sum(v.startswith("llm:") for v in groups.values()),
            "requests": server.requests, "stalls": server.stalls, "max_active": server.max_active,
            "instances": len(layout.instances), "llm_budget_groups": layout.stats.get("llm_budget_groups"),
            "prompt_tokens": layout.stats.get("prompt_tokens"), "completion_tokens": layout.stats.get("completion_tokens"),
            "_layout": [i.to_json() for i in layout.instances]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--assets", default=None, help="catalog folder (default: the built-in procedural library)")
    ap.add_argument("--seed", type=int, default=3)
    ap.add_argument("--latency", type=float, default=2.0, help="seconds per answer")
    ap.add_argument("--token-s", type=float, default=0.0,
                    help="extra seconds per answer token (answer characters / 4): 0.02 is 50 tokens/s")
    ap.add_argument("--stall-every", type=int, default=0, help="stall on 1 prompt in K (0 = never)")
    ap.add_argument("--stall-s", type=float, default=45.0)
    ap.add_argument("--timeout", type=float, default=60.0, help="llm.timeout_s")
    ap.add_argument("--concurrency", type=int, default=8)
    ap.add_argument("--scene-budget", type=float, default=None, help="llm.scene_budget_s")
    ap.add_argument("--modes", default="serial,concurrent", help="comma-separated: serial, concurrent, batched")
    ap.add_argument("--on-top-batch", type=int, default=8, help="llm.on_top_batch of the batched mode")
    ap.add_argument("--answer-formats", default="full",
                    help="comma-separated llm.answer_format values (full, compact): every mode runs in each")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    rows = []
    modes = args.modes.split(",")
    unknown = sorted(set(modes) - {"serial", "concurrent", "batched"})
    if unknown:
        ap.error(f"unknown mode(s) {', '.join(unknown)}: use serial, concurrent, batched")
    forms = args.answer_formats.split(",")
    if sorted(set(forms) - {"full", "compact"}):
        ap.error("--answer-formats takes full and/or compact")
    for form in forms:
        for mode in modes:
            with tempfile.TemporaryDirectory(prefix="bench-llm-") as cache:
                rows.append(run_once(args, mode, cache, form))
            print(f"{rows[-1]['mode']}: {rows[-1]['seconds']} s", file=sys.stderr)
    same = len({json.dumps(r.pop("_layout"), sort_keys=True) for r in rows}) == 1
    report = {"latency_s": args.latency, "token_s": args.token_s, "answer_formats": forms, "stall_every": args.stall_every, "stall_s": args.stall_s,
              "concurrency": args.concurrency, "scene_budget_s": args.scene_budget, "seed": args.seed,
              "on_top_batch": args.on_top_batch if "batched" in modes else None, "runs": rows, "same_layout": same}
    if len(rows) == 2 and rows[1]["seconds"] > 0:
        report["speedup"] = round(rows[0]["seconds"] / rows[1]["seconds"], 2)
    if len(rows) >= 2:  # every mode against the first
        report["speedups"] = {r["mode"]: round(rows[0]["seconds"] / r["seconds"], 2) for r in rows if r["seconds"] > 0}
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        for r in rows:
            print(f"{r['mode']:>10}: {r['seconds']:7.1f} s  {r['groups']} groups ({r['llm_groups']} by the LLM), "
                  f"{r['requests']} requests, {r['stalls']} stalls, at most {r['max_active']} at once, "
                  f"{r['instances']} instances")
        if "speedups" in report:
            print(f"speed-up against {rows[0]['mode']}: {report['speedups']}; same layout: {same}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
