"""A small, hardened client for OpenAI-compatible ``/chat/completions`` endpoints (stdlib only).

What it guarantees:

* **Bounded time.** Every attempt has a deadline of ``timeout_s``: the socket time-out is reset
  to the time left before every read, and a watchdog shuts the socket down at the deadline, so a
  server that accepts the connection and never answers (or trickles bytes) cannot hang a run.
  A stalled attempt is not retried (a server that stalled once usually stalls again).
* **Retries** with exponential back-off (``backoff_s * 2**attempt``; ``Retry-After`` honoured up
  to a cap) on connection errors and on HTTP 408/409/425/429/5xx. Other 4xx answers fail at once.
* **Bounded size.** ``max_response_bytes`` is enforced while the body is read (and from
  ``Content-Length`` before), never after.
* **Bounded concurrency across processes**: ``concurrency`` lock files per endpoint under the
  cache folder, taken with ``fcntl.flock`` (released by the OS if a worker dies).
* **Circuit breaker**: after ``max_failures`` consecutive failed calls, every client of that
  endpoint in the process stops calling it for ``BREAKER_COOLDOWN_S`` (then one probe call is let
  through); cached answers are still served. A new planner per scene shares the state.
* **Secrets**: the API key is read from the environment variable named by ``api_key_env`` at
  request time and only ever placed in the ``Authorization`` header: never logged, cached, or
  part of an error message.
* ``response_format: {"type": "json_object"}`` is sent when ``json_mode`` is on; a server that
  rejects it (HTTP 400/422) is asked again without it, once, and never again.
"""

from __future__ import annotations

import http.client
import json
import logging
import os
import socket
import ssl
import threading
import time
import urllib.parse
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Iterator

try:
    import fcntl
except ImportError:  # not POSIX (Windows): request slots are counted per process
    fcntl = None  # type: ignore[assignment]

from ..config import LLMConfig
from ..core.errors import ConfigError, LLMError, shown
from ..core.rng import stable_hash
from .cache import CachedAnswer, ResponseCache, cache_key

log = logging.getLogger(__name__)

RETRY_STATUS = frozenset({408, 409, 425, 429, 500, 502, 503, 504})
RETRY_AFTER_CAP_S = 30.0
_CHUNK = 65536


BREAKER_COOLDOWN_S = 300.0


@dataclass
class _EndpointState:
    """What a process has learnt about one endpoint: its failure streak and json_mode support."""

    json_mode: bool
    failures: int = 0
    last_failure: float = 0.0


_STATES: dict[tuple[str, str, str], _EndpointState] = {}
_STATES_LOCK = threading.Lock()


@dataclass
class Usage:
    """Mutable counters a caller passes to :meth:`ChatClient.complete` to account one task.

    ``calls`` counts HTTP requests sent (retries included); ``seconds`` is wall time spent in
    :meth:`ChatClient.complete` (waiting for a slot, requests, back-off).
    """

    calls: int = 0
    cache_hits: int = 0
    prompt_tokens: int = 0
    completion_tokens: int = 0
    seconds: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        return {"llm_calls": self.calls, "cache_hits": self.cache_hits, "prompt_tokens": self.prompt_tokens,
                "completion_tokens": self.completion_tokens, "seconds": round(self.seconds, 4)}


@dataclass(frozen=True)
class ChatAnswer:
    content: str
    cached: bool
    prompt_tokens: int
    completion_tokens: int
    finish_reason: str = ""  # "length" means the answer was cut off at max_tokens


class _Stall(Exception):
    pass


class _TooLarge(Exception):
    pass


@dataclass(frozen=True)
class _Endpoint:
    scheme: str
    host: str
    port: int
    path: str

    @property
    def display(self) -> str:  # never includes credentials
        return f"{self.scheme}://{self.host}:{self.port}{self.path}"


def parse_endpoint(base_url: str) -> _Endpoint:
    """Split ``base_url`` (e.g. ``http://127.0.0.1:8000/v1``) into the chat-completions target."""
    u = urllib.parse.urlsplit(base_url.strip())
    if u.scheme not in ("http", "https") or not u.hostname:
        raise ConfigError(f"llm.base_url {base_url!r}: expected http(s)://host[:port]/path, "
                          "e.g. https://api.openai.com/v1 or http://127.0.0.1:8000/v1")
    if u.username or u.password:
        raise ConfigError("llm.base_url must not contain credentials; put the key in the environment "
                          "variable named by llm.api_key_env")
    port = u.port or (443 if u.scheme == "https" else 80)
    path = u.path.rstrip("/")
    if not path.endswith("/chat/completions"):
        path += "/chat/completions"
    if u.query:
        path += "?" + u.query
    return _Endpoint(u.scheme, u.hostname, port, path)


class ChatClient:
    """Send chat-completion requests for one model; see the module docstring for guarantees."""

    def __init__(self, cfg: LLMConfig, *, model: str | None = None, cache: ResponseCache | None = None) -> None:
        if not cfg.base_url:
            raise ConfigError("llm.base_url is not set (use --llm-base-url or the config file)")
        model = model or cfg.model
        if not model:
            raise ConfigError("llm.model is not set (use --llm-model or the config file)")
        self.cfg = cfg
        self.model = model
        self.endpoint = parse_endpoint(cfg.base_url)
        self.cache = cache if cache is not None else ResponseCache(cfg.cache_dir)
        self._lock_dir = self.cache.folder / "locks" / stable_hash(self.endpoint.display)
        # shared by every client of this endpoint, model and cache in the process (one per scene)
        key = (self.endpoint.display, model, str(self.cache.folder))
        with _STATES_LOCK:
            self._state = _STATES.setdefault(key, _EndpointState(json_mode=cfg.json_mode))

    # ------------------------------------------------------------------------------------------
    @property
    def json_mode(self) -> bool:
        return self._state.json_mode

    @property
    def consecutive_failures(self) -> int:
        return self._state.failures

    @property
    def disabled(self) -> bool:
        """True while the circuit breaker is open: ``max_failures`` failed calls in a row, and
        less than ``BREAKER_COOLDOWN_S`` since the last one (then one probe call is let through)."""
        st = self._state
        return st.failures >= self.cfg.max_failures and time.monotonic() - st.last_failure < BREAKER_COOLDOWN_S

    def complete(self, messages: list[dict[str, Any]], *, usage: Usage | None = None,
                 use_cache: bool = True) -> ChatAnswer:
        """The assistant's text for ``messages`` (from the cache when possible).

        Raises :class:`LLMError` when the endpoint fails after retries, stalls, answers too much
        or answers something that is not a chat completion.
        """
        usage = usage if usage is not None else Usage()
        t0 = time.monotonic()
        try:
            key = cache_key(self.model, messages, self.cfg.temperature)
            if use_cache:
                hit = self.cache.get(key)
                if hit is not None:
                    usage.cache_hits += 1
                    log.debug("cache hit %s (%s)", key[:12], self.model)
                    return ChatAnswer(hit.content, True, hit.prompt_tokens, hit.completion_tokens, hit.finish_reason)
            if self.disabled:
                raise LLMError(f"{self.endpoint.display}: skipped, the endpoint failed "
                               f"{self.consecutive_failures} times in a row")
            try:
                answer = self._call(messages, usage)
            except LLMError:
                with _STATES_LOCK:
                    self._state.failures += 1
                    self._state.last_failure = time.monotonic()
                raise
            self._state.failures = 0
            usage.prompt_tokens += answer.prompt_tokens
            usage.completion_tokens += answer.completion_tokens
            secret = self._api_key()
            if len(secret) >= 8 and secret in answer.content:
                log.warning("%s: the answer contains the API key; not caching it", self.endpoint.display)
            elif use_cache:
                self.cache.put(key, self.model,
                               CachedAnswer(answer.content, answer.prompt_tokens, answer.completion_tokens,
                                            answer.finish_reason))
            return answer
        finally:
            usage.seconds += time.monotonic() - t0

    # ------------------------------------------------------------------------------------------
    def _api_key(self) -> str:
        return os.environ.get(self.cfg.api_key_env, "").strip()

    def _body(self, messages: list[dict[str, Any]]) -> bytes:
        body: dict[str, Any] = {"model": self.model, "messages": messages, "temperature": self.cfg.temperature,
                                "max_tokens": self.cfg.max_tokens}
        if self.json_mode:
            body["response_format"] = {"type": "json_object"}
        return json.dumps(body, ensure_ascii=False).encode("utf-8")

    def _call(self, messages: list[dict[str, Any]], usage: Usage) -> ChatAnswer:
        with self._slot():
            attempt = 0
            last = "no attempt made"
            while True:
                json_sent = self.json_mode
                usage.calls += 1
                delay = 0.0
                try:
                    status, headers, data = self._request(self._body(messages))
                except _Stall:
                    raise LLMError(f"{self.endpoint.display}: no complete answer within "
                                   f"{self.cfg.timeout_s:g} s (llm.timeout_s)") from None
                except _TooLarge:
                    raise LLMError(f"{self.endpoint.display}: answer larger than "
                                   f"{self.cfg.max_response_bytes} bytes (llm.max_response_bytes)") from None
                except (OSError, http.client.HTTPException) as e:
                    last = f"connection failed ({type(e).__name__}: {e})"
                else:
                    if status == 200:
                        return self._parse(data)
                    snippet = self._snippet(data)
                    if status in (400, 422) and json_sent:
                        log.info("%s: HTTP %d with response_format; asking again without it (%s)",
                                 self.endpoint.display, status, snippet)
                        self._state.json_mode = False
                        continue
                    if status not in RETRY_STATUS:
                        raise LLMError(f"{self.endpoint.display}: HTTP {status} ({snippet})")
                    last = f"HTTP {status} ({snippet})"
                    delay = _retry_after(headers.get("retry-after"))
                if attempt >= self.cfg.retries:
                    raise LLMError(f"{self.endpoint.display}: failed after {attempt + 1} attempt(s): {last}")
                delay = max(delay, self.cfg.backoff_s * (2 ** attempt))
                log.warning("%s: %s; retry %d/%d in %.2f s", self.endpoint.display, last, attempt + 1,
                            self.cfg.retries, delay)
                time.sleep(delay)
                attempt += 1

    def _snippet(self, data: bytes) -> str:
        """The start of an answer body for a message: the key masked, controls escaped, cut short."""
        text = data[:300].decode("utf-8", "replace").replace("\n", " ").strip()
        secret = self._api_key()
        return shown(text.replace(secret, "***") if secret else text)

    def _parse(self, data: bytes) -> ChatAnswer:
        try:
            d = json.loads(data.decode("utf-8"))
            choice = d["choices"][0]
            msg = choice["message"]
            content = msg.get("content")
            if content is None:
                raise ValueError("message has no content")
            if isinstance(content, list):  # content parts
                content = "".join(p.get("text", "") for p in content if isinstance(p, dict))
            if not isinstance(content, str):
                raise ValueError(f"content is {type(content).__name__}, not text")
            u = d.get("usage") or {}
            return ChatAnswer(content, False, int(u.get("prompt_tokens") or 0), int(u.get("completion_tokens") or 0),
                              str(choice.get("finish_reason") or ""))
        except (ValueError, KeyError, IndexError, TypeError, AttributeError, UnicodeDecodeError) as e:
            raise LLMError(f"{self.endpoint.display}: not a chat completion ({e}): {self._snippet(data)}") from None

    def _request(self, body: bytes) -> tuple[int, dict[str, str], bytes]:
        """One POST with a hard deadline; returns (status, lower-cased headers, body)."""
        ep = self.endpoint
        deadline = time.monotonic() + self.cfg.timeout_s
        conn: http.client.HTTPConnection
        if ep.scheme == "https":
            conn = http.client.HTTPSConnection(ep.host, ep.port, timeout=self.cfg.timeout_s,
                                               context=ssl.create_default_context())
        else:
            conn = http.client.HTTPConnection(ep.host, ep.port, timeout=self.cfg.timeout_s)
        headers = {"Content-Type": "application/json", "Accept": "application/json",
                   "User-Agent": "assist3d-llm/1"}
        secret = self._api_key()
        if secret:
            headers["Authorization"] = f"Bearer {secret}"
        fired = threading.Event()
        watchdog: threading.Timer | None = None
        try:
            try:
                conn.connect()
            except (socket.timeout, TimeoutError):
                raise _Stall from None
            sock = conn.sock

            def _kill() -> None:
                fired.set()
                try:
                    sock.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass

            watchdog = threading.Timer(max(0.0, deadline - time.monotonic()), _kill)
            watchdog.daemon = True
            watchdog.start()
            try:
                sock.settimeout(_left(deadline))
                conn.request("POST", ep.path, body=body, headers=headers)
                sock.settimeout(_left(deadline))
                resp = conn.getresponse()
                length = resp.getheader("Content-Length")
                if length is not None and length.isdigit() and int(length) > self.cfg.max_response_bytes:
                    raise _TooLarge
                data = _read_capped(resp, sock, deadline, self.cfg.max_response_bytes)
            except (socket.timeout, TimeoutError):
                raise _Stall from None
            except (OSError, http.client.HTTPException):
                if fired.is_set() or time.monotonic() >= deadline:
                    raise _Stall from None
                raise
            if fired.is_set():
                raise _Stall
            return resp.status, {k.lower(): v for k, v in resp.getheaders()}, data
        finally:
            if watchdog is not None:
                watchdog.cancel()
            conn.close()

    @contextmanager
    def _slot(self) -> Iterator[None]:
        """Hold one of ``concurrency`` request slots shared by every process using this cache."""
        if fcntl is None:  # not POSIX: the limit holds per process only
            with _process_semaphore(self.cfg.concurrency):
                yield
            return
        self._lock_dir.mkdir(parents=True, exist_ok=True)
        wait_s = self.cfg.timeout_s * (self.cfg.retries + 1) + self.cfg.backoff_s * (2 ** self.cfg.retries)
        give_up = time.monotonic() + wait_s
        pause = 0.02
        while True:
            for i in range(self.cfg.concurrency):
                fd = os.open(self._lock_dir / f"slot-{i}.lock", os.O_RDWR | os.O_CREAT, 0o600)
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except OSError:
                    os.close(fd)
                    continue
                try:
                    yield
                finally:
                    fcntl.flock(fd, fcntl.LOCK_UN)
                    os.close(fd)
                return
            if time.monotonic() >= give_up:
                raise LLMError(f"{self.endpoint.display}: no free request slot after {wait_s:.0f} s "
                               f"(llm.concurrency = {self.cfg.concurrency}, lock folder {self._lock_dir})")
            time.sleep(pause)
            pause = min(pause * 2, 0.1)


_SEMAPHORES: dict[int, threading.BoundedSemaphore] = {}


@contextmanager
def _process_semaphore(n: int) -> Iterator[None]:
    sem = _SEMAPHORES.setdefault(n, threading.BoundedSemaphore(n))
    with sem:
        yield


def _left(deadline: float) -> float:
    left = deadline - time.monotonic()
    if left <= 0:
        raise _Stall
    return left


def _read_capped(resp: http.client.HTTPResponse, sock: socket.socket, deadline: float, cap: int) -> bytes:
    """Read the body in chunks, failing as soon as it passes ``cap`` bytes or the deadline."""
    chunks: list[bytes] = []
    total = 0
    while True:
        sock.settimeout(_left(deadline))
        chunk = resp.read1(_CHUNK)
        if not chunk:
            return b"".join(chunks)
        total += len(chunk)
        if total > cap:
            raise _TooLarge
        chunks.append(chunk)


def _retry_after(value: str | None) -> float:
    if not value:
        return 0.0
    try:
        return min(max(float(value), 0.0), RETRY_AFTER_CAP_S)
    except ValueError:
        return 0.0

