"""A scripted chat-completions server on 127.0.0.1 for the LLM tests (imported by test_llm_*.py).

Each request takes the next step of the script (the last step repeats): a status, an assistant
text, an optional delay before answering (a stall), a raw body, or an endless body without a
Content-Length. Every request's headers and JSON body are recorded, and every request is checked
against the chat-completions protocol: leaving the ``with`` block fails the test if the client
sent a malformed request or put the API key anywhere but the Authorization header.
"""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Callable

SENTINEL = "sk-test-SENTINEL-9f1c2e7d4b"


@dataclass
class Step:
    content: str = ""
    status: int = 200
    sleep: float = 0.0
    raw: bytes | None = None
    endless: bool = False  # stream bytes with no Content-Length until the client hangs up
    reject_json_mode: bool = False  # answer 400 when response_format is present
    trickle: bool = False  # send a complete answer one byte every 0.1 s
    finish_reason: str = "stop"
    headers: dict = field(default_factory=dict)


def completion(content: str, prompt_tokens: int = 11, completion_tokens: int = 7, finish_reason: str = "stop") -> bytes:
    return json.dumps({
        "id": "chatcmpl-test", "object": "chat.completion", "model": "fake",
        "choices": [{"index": 0, "message": {"role": "assistant", "content": content}, "finish_reason": finish_reason}],
        "usage": {"prompt_tokens": prompt_tokens, "completion_tokens": completion_tokens,
                  "total_tokens": prompt_tokens + completion_tokens},
    }).encode()


class FakeServer:
    def __init__(self, steps: list[Step], responder: Callable[[dict], Step] | None = None) -> None:
        """``responder(request_json) -> Step``, when given, decides every answer instead of ``steps``."""
        self.steps = list(steps) or [Step()]
        self.responder = responder
        self.requests: list[dict] = []
        self.active = 0
        self.max_active = 0
        self.protocol_errors: list[str] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        owner = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args) -> None:  # keep test output quiet
                pass

            def do_POST(self) -> None:
                body = self.rfile.read(int(self.headers.get("Content-Length", 0)))
                problems = protocol_problems(self.path, dict(self.headers), body)
                with owner._lock:
                    owner.protocol_errors.extend(problems)
                    owner.requests.append({"path": self.path, "headers": dict(self.headers),
                                           "json": json.loads(body)})
                    step = (owner.responder(owner.requests[-1]["json"]) if owner.responder else
                            owner.steps[min(len(owner.requests) - 1, len(owner.steps) - 1)])
                    owner.active += 1
                    owner.max_active = max(owner.max_active, owner.active)
                try:
                    owner._answer(self, step)
                except (BrokenPipeError, ConnectionResetError):
                    pass
                finally:
                    with owner._lock:
                        owner.active -= 1

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.httpd.daemon_threads = True
        self.thread = threading.Thread(target=self.httpd.serve_forever, args=(0.02,), daemon=True)

    def _answer(self, h: BaseHTTPRequestHandler, step: Step) -> None:
        if step.sleep:
            self._stop.wait(step.sleep)
        if step.reject_json_mode and "response_format" in self.requests[-1]["json"]:
            data = b'{"error": {"message": "response_format is not supported"}}'
            h.send_response(400)
            h.send_header("Content-Length", str(len(data)))
            h.end_headers()
            h.wfile.write(data)
            return
        if step.endless:
            h.send_response(200)
            h.send_header("Content-Type", "application/json")
            h.send_header("Connection", "close")
            h.end_headers()
            chunk = b" " * 4096
            t_end = time.monotonic() + 10
            while time.monotonic() < t_end and not self._stop.is_set():
                h.wfile.write(chunk)
            return
        data = step.raw if step.raw is not None else (
            completion(step.content, finish_reason=step.finish_reason) if step.status == 200 else
            b'{"error": {"message": "scripted failure"}}')
        h.send_response(step.status)
        h.send_header("Content-Type", "application/json")
        h.send_header("Content-Length", str(len(data)))
        for k, v in step.headers.items():
            h.send_header(k, v)
        h.end_headers()
        if step.trickle:
            for k in range(len(data)):
                if self._stop.wait(0.1):
                    return
                h.wfile.write(data[k:k + 1])
                h.wfile.flush()
            return
        h.wfile.write(data)

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.httpd.server_address[1]}/v1"

    def __enter__(self) -> "FakeServer":
        self.thread.start()
        return self

    def __exit__(self, exc_type, *exc) -> None:
        self._stop.set()
        self.httpd.shutdown()
        self.httpd.server_close()
        if exc_type is None:
            assert not self.protocol_errors, f"malformed chat-completions requests: {self.protocol_errors}"


def protocol_problems(path: str, headers: dict, body: bytes) -> list[str]:
    """What is wrong with one request for an OpenAI-compatible /chat/completions endpoint."""
    out = []
    if not path.endswith("/chat/completions"):
        out.append(f"POST to {path!r}, not .../chat/completions")
    if SENTINEL.encode() in body:
        out.append("the API key is in the request body")
    try:
        data = json.loads(body)
    except ValueError:
        return out + ["body is not JSON"]
    if not isinstance(data.get("model"), str) or not data["model"]:
        out.append("no model name")
    msgs = data.get("messages")
    if not isinstance(msgs, list) or not msgs:
        out.append("no messages")
    else:
        for m in msgs:
            if not isinstance(m, dict) or m.get("role") not in ("system", "user", "assistant"):
                out.append(f"bad message role in {str(m)[:80]}")
            elif not isinstance(m.get("content"), (str, list)):
                out.append(f"bad message content type {type(m.get('content')).__name__}")
    auth = {k.lower(): v for k, v in headers.items()}.get("authorization")
    if auth is not None and not auth.startswith("Bearer "):
        out.append("Authorization header is not a Bearer token")
    return out


def files_containing(secret: str, *folders: Path) -> list[Path]:
    """Every file under ``folders`` whose bytes contain ``secret``."""
    hits = []
    for folder in folders:
        for p in Path(folder).rglob("*"):
            if p.is_file() and secret.encode() in p.read_bytes():
                hits.append(p)
    return hits
