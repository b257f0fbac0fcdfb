"""A Zenoh client run as a separate process by the service tests (and usable by hand).

    python tests/service/zenoh_client.py ENDPOINT < steps.json > answers.json

``steps`` is a JSON list; each step is one of
  {"query": KEY, "payload": JSON or raw string, "timeout_s": S}  -> {"replies": [{"ok", "encoding", "payload"}]}
  {"queries": [{"query": KEY, "payload": ...}, ...]}              -> {"replies": [...], "order": [i, ...]}
                                                                     (sent together; ``order`` = the query
                                                                     indices in the order they were answered)
  {"put": KEY, "payload": JSON}                                    -> {}
  {"subscribe": KEY_EXPR}                                          -> {} (samples are collected from then on)
  {"wait": KEY_SUFFIX, "until": {field: value}, "timeout_s": S}   -> {"samples": [...]} (stops at the first
                                                                     sample on a key ending in KEY_SUFFIX whose
                                                                     payload has those fields)
  {"wait_all": [KEY_SUFFIX, ...], "until": ..., "timeout_s": S}    -> the same, once every suffix has had one
  {"liveliness": KEY_EXPR}                                         -> {"tokens": [key, ...]}
A query or put may carry "attachment" (a string, e.g. "Bearer <token>"); a query "consolidation": "none" has
every reply kept (to count how many instances answered), each reply then with its "replier" id.
  {"sleep": S}                                                     -> {}
and the answers (one per step) are printed as a JSON list. The client connects in client mode to
ENDPOINT only, with multicast scouting off.
"""

from __future__ import annotations

import json
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import zenoh


def _decode(payload: zenoh.ZBytes | None) -> Any:
    if payload is None:
        return None
    text = payload.to_bytes().decode()
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def _reply(reply: zenoh.Reply) -> dict[str, Any]:
    sample = reply.ok if reply.ok is not None else reply.err
    assert sample is not None
    return {"ok": reply.ok is not None, "encoding": str(sample.encoding), "payload": _decode(sample.payload),
            "replier": str(reply.replier_id) if reply.replier_id is not None else None}


def _get_options(step: dict[str, Any]) -> dict[str, Any]:
    options: dict[str, Any] = {"payload": _encode(step["payload"]), "timeout": float(step.get("timeout_s", 30))}
    if step.get("attachment") is not None:
        options["attachment"] = step["attachment"].encode()
    if step.get("consolidation") == "none":
        options["consolidation"] = zenoh.ConsolidationMode.NONE
    return options


def _encode(payload: Any) -> bytes:
    return payload.encode() if isinstance(payload, str) else json.dumps(payload).encode()


def _concurrent_queries(session: zenoh.Session, queries: list[dict[str, Any]]) -> dict[str, Any]:
    done = threading.Semaphore(0)
    got: list[list[dict[str, Any]]] = [[] for _ in queries]
    order: list[int] = []

    def on_reply(index: int) -> Callable[[zenoh.Reply], None]:
        def record(reply: zenoh.Reply) -> None:
            got[index].append(_reply(reply))
            order.append(index)

        return record

    for i, query in enumerate(queries):
        session.get(query["query"], zenoh.handlers.Callback(on_reply(i), done.release), **_get_options(query))
    for _ in queries:
        done.acquire(timeout=60)
    # one query, one reply as a rule: its reply alone (a query answered more than once keeps them all)
    return {"replies": [g[0] if len(g) == 1 else (g or None) for g in got], "all_replies": got, "order": order}


def _wait(samples: list[tuple[str, Any]], arrived: threading.Condition, suffixes: list[str], want: dict[str, Any],
          timeout_s: float) -> dict[str, Any]:
    """Until, for every suffix, a sample whose key ends with it matches ``want`` (or the timeout)."""
    deadline = time.monotonic() + timeout_s
    missing = set(suffixes)
    seen = 0  # samples already looked at

    def matched() -> bool:
        nonlocal seen
        for key, data in samples[seen:]:
            if isinstance(data, dict) and all(data.get(k) == v for k, v in want.items()):
                missing.difference_update([suffix for suffix in missing if key.endswith(suffix)])
        seen = len(samples)
        return not missing

    with arrived:
        while not matched() and time.monotonic() < deadline:
            arrived.wait(timeout=0.1)
        return {"samples": [{"key": k, "payload": d} for k, d in samples]}


def run(endpoint: str, steps: list[dict[str, Any]]) -> list[dict[str, Any]]:
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    samples: list[tuple[str, Any]] = []
    arrived = threading.Condition()

    def on_sample(sample: zenoh.Sample) -> None:
        with arrived:
            samples.append((str(sample.key_expr), _decode(sample.payload)))
            arrived.notify_all()

    answers: list[dict[str, Any]] = []
    subscribers = []
    with zenoh.open(conf) as session:
        for step in steps:
            if "query" in step:
                replies = [_reply(reply) for reply in session.get(step["query"], **_get_options(step))]
                answers.append({"replies": replies})
            elif "queries" in step:
                answers.append(_concurrent_queries(session, step["queries"]))
            elif "put" in step:
                attachment = step.get("attachment")
                # BLOCK, as a robot sending its goal would: the default (DROP) may lose a sample on a busy machine
                session.put(step["put"], _encode(step["payload"]), encoding=zenoh.Encoding.APPLICATION_JSON,
                            attachment=None if attachment is None else attachment.encode(),
                            congestion_control=zenoh.CongestionControl.BLOCK)
                answers.append({})
            elif "subscribe" in step:
                subscribers.append(session.declare_subscriber(step["subscribe"], on_sample))
                answers.append({})
            elif "wait" in step or "wait_all" in step:
                suffixes = step["wait_all"] if "wait_all" in step else [step["wait"]]
                answers.append(_wait(samples, arrived, suffixes, step.get("until", {}),
                                     float(step.get("timeout_s", 30))))
            elif "liveliness" in step:
                tokens = [str(r.ok.key_expr) for r in session.liveliness().get(step["liveliness"], timeout=5)
                          if r.ok is not None]
                answers.append({"tokens": tokens})
            elif "sleep" in step:
                time.sleep(float(step["sleep"]))
                answers.append({})
        for subscriber in subscribers:
            subscriber.undeclare()
    return answers


if __name__ == "__main__":
    json.dump(run(sys.argv[1], json.load(sys.stdin)), sys.stdout)
