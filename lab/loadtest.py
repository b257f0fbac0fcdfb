"""Load test of the service on loopback: ``/v1/plan`` throughput and latency, Zenoh query round trips.

    python -m lab.loadtest [--duration 10] [--concurrency 4] [--workers 1 2] [--zenoh-queries 20]
    python -m lab.loadtest --fleet [--duration 10] [--workers 1]      (= sphereplan bench --suite load)

For each worker count it starts ``sphereplan serve`` on free loopback ports (HTTP and a Zenoh peer),
waits until the pool is warm, then keeps ``--concurrency`` clients posting the shipped problems
(``maps/problems/*.json``, solvable ones unless ``--all``) round-robin for ``--duration`` seconds and
prints requests/s and p50/p99 latency. With the last server it then times, one request at a time, the
same plan over HTTP and as a ``sphereplan/plan`` Zenoh query, plus a query answered without planning
(a validation error: the transport's own round trip). ``--fleet`` (:func:`fleet_main`) starts two instances
and HAProxy (:mod:`lab.fleet`, the shipped ``deploy/haproxy/sphereplan.cfg``) and prints throughput and p50/p99
for 1, 4 and 16 clients against one instance and against the two behind the balancer, ``/healthz`` latency
while 16 clients send MB-sized bodies, and what a SIGKILLed instance costs. Everything is bounded in time;
nothing leaves the machine. A benchmark prints a table; it asserts nothing.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx

REPO = Path(__file__).resolve().parent.parent
JSON = {"content-type": "application/json"}


def _free_port() -> int:
    import socket

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def _percentile(values: list[float], q: float) -> float:
    if not values:
        return float("nan")
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q / 100 * (len(ordered) - 1)))]


@dataclass
class Served:
    url: str
    zenoh_endpoint: str
    startup_s: float


@contextmanager
def serve(workers: int, max_in_flight: int) -> Iterator[Served]:
    """A ``sphereplan serve`` subprocess on free loopback ports; stopped with SIGINT on exit."""
    port, zport = _free_port(), _free_port()
    endpoint = f"tcp/127.0.0.1:{zport}"
    log = tempfile.TemporaryFile()
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "service.cli", "serve", "--port", str(port), "--zenoh-listen", endpoint,
         "--workers", str(workers), "--max-in-flight", str(max_in_flight)],
        cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO)}, stdout=log, stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}"
    try:
        while True:
            if proc.poll() is not None:
                log.seek(0)
                raise RuntimeError(f"serve exited with {proc.returncode}: {log.read().decode()[-2000:]}")
            try:
                if httpx.get(url + "/readyz", timeout=1).status_code == 200:
                    break
            except httpx.HTTPError:
                pass
            if time.perf_counter() - t0 > 120:
                raise RuntimeError("serve not ready within 120 s")
            time.sleep(0.1)
        yield Served(url, endpoint, time.perf_counter() - t0)
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
        log.close()


def problem_requests(include_unsolvable: bool) -> list[dict[str, Any]]:
    """The shipped problems as ``/v1/plan`` bodies."""
    from planner.maps.problems import list_problems

    bodies = []
    for p in list_problems():
        if p.solvable or include_unsolvable:
            bodies.append({"map": Path(p.map).stem, "start": dict(zip(("x", "y", "yaw"), p.start, strict=True)),
                           "goal": dict(zip(("x", "y", "yaw"), p.goal, strict=True)), "time_limit_s": p.time_limit_s})
    return bodies


async def http_load(url: str, bodies: list[dict[str, Any]], concurrency: int, duration_s: float) -> dict[str, Any]:
    """Closed loop: ``concurrency`` clients post bodies round-robin until ``duration_s`` has passed."""
    latencies: list[float] = []
    planning: list[float] = []
    statuses: dict[int, int] = {}
    counter = iter(range(10**9))
    t0 = time.perf_counter()
    async with httpx.AsyncClient(base_url=url, timeout=120) as client:

        async def worker() -> None:
            while time.perf_counter() - t0 < duration_s:
                body = bodies[next(counter) % len(bodies)]
                start = time.perf_counter()
                response = await client.post("/v1/plan", json=body)
                latencies.append(time.perf_counter() - start)
                statuses[response.status_code] = statuses.get(response.status_code, 0) + 1
                if response.status_code in (200, 422):
                    planning.append(float(response.json().get("planning_time_s", 0.0)))
                if response.status_code == 503:
                    await asyncio.sleep(float(response.headers.get("retry-after", "1")))

        await asyncio.gather(*(worker() for _ in range(concurrency)))
    elapsed = time.perf_counter() - t0
    return {"requests": len(latencies), "statuses": statuses, "elapsed_s": elapsed, "rps": len(latencies) / elapsed,
            "p50_ms": 1000 * _percentile(latencies, 50), "p99_ms": 1000 * _percentile(latencies, 99),
            "plan_ms": 1000 * statistics.fmean(planning) if planning else float("nan")}


def timed(fn: Callable[[], Any], n: int) -> list[float]:
    out = []
    for _ in range(n):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return out


def round_trips(served: Served, body: dict[str, Any], n: int) -> dict[str, list[float]]:
    """Sequential round trips of one plan over HTTP and Zenoh, and of requests answered without planning."""
    import zenoh

    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", json.dumps([served.zenoh_endpoint]))
    conf.insert_json5("scouting/multicast/enabled", "false")
    payload = json.dumps(body).encode()
    bad = json.dumps({**body, "time_limit_s": -1}).encode()
    with httpx.Client(base_url=served.url, timeout=120) as client, zenoh.open(conf) as session:

        def query(data: bytes) -> None:
            replies = list(session.get("sphereplan/plan", payload=data, timeout=120))
            if len(replies) != 1:
                raise RuntimeError(f"expected one reply, got {len(replies)}")

        query(payload)  # connect and warm the planner cache for this map
        client.post("/v1/plan", json=body)
        return {
            "HTTP POST /v1/plan": timed(lambda: client.post("/v1/plan", json=body), n),
            "Zenoh get sphereplan/plan": timed(lambda: query(payload), n),
            "HTTP GET /healthz": timed(lambda: client.get("/healthz"), n),
            "HTTP POST /v1/plan, rejected (422)": timed(lambda: client.post("/v1/plan", content=bad, headers=JSON), n),
            "Zenoh get sphereplan/plan, rejected (reply_err)": timed(lambda: query(bad), n),
        }


# ------------------------------------------------------------------------------------------- the fleet suite


def _load_avg() -> str:
    one, five, _ = os.getloadavg()
    return f"{one:.1f}/{five:.1f}"


async def _safe_load(url: str, bodies: list[dict[str, Any]], concurrency: int, duration_s: float
                     ) -> dict[str, Any]:
    """:func:`http_load` that also counts transport errors (a refused or reset connection) instead of raising."""
    errors = 0

    async def guarded() -> dict[str, Any]:
        nonlocal errors
        try:
            return await http_load(url, bodies, concurrency, duration_s)
        except httpx.HTTPError:
            errors += 1
            return {"requests": 0, "statuses": {}, "rps": 0.0, "p50_ms": float("nan"), "p99_ms": float("nan")}

    result = await guarded()
    result["errors"] = errors
    return result


async def failover_run(url: str, bodies: list[dict[str, Any]], concurrency: int, duration_s: float,
                       kill: Callable[[], None]) -> dict[str, Any]:
    """``concurrency`` clients through the balancer for ``duration_s``; ``kill()`` one instance a third of the way
    in. Every request sent is counted: answered 200, answered otherwise, or lost (a transport error)."""
    statuses: dict[int, int] = {}
    lost = 0
    latencies_after: list[float] = []
    killed_at: float | None = None
    counter = iter(range(10**9))
    t0 = time.perf_counter()
    async with httpx.AsyncClient(base_url=url, timeout=180) as client:

        async def worker() -> None:
            nonlocal lost
            while time.perf_counter() - t0 < duration_s:
                body = bodies[next(counter) % len(bodies)]
                start = time.perf_counter()
                try:
                    response = await client.post("/v1/plan", json=body)
                except httpx.HTTPError:
                    lost += 1
                    continue
                if killed_at is not None and start >= killed_at - 5:
                    latencies_after.append(time.perf_counter() - start)
                statuses[response.status_code] = statuses.get(response.status_code, 0) + 1

        async def killer() -> None:
            nonlocal killed_at
            await asyncio.sleep(duration_s / 3)
            killed_at = time.perf_counter()
            await asyncio.to_thread(kill)

        await asyncio.gather(killer(), *(worker() for _ in range(concurrency)))
    return {"statuses": statuses, "lost": lost, "sent": sum(statuses.values()) + lost,
            "p99_around_kill_ms": 1000 * _percentile(latencies_after, 99),
            "max_around_kill_ms": 1000 * max(latencies_after, default=float("nan"))}


def _probe_healthz(url: str, duration_s: float, out: Any) -> None:
    """In its own process (as a balancer's health checker is): ``GET /healthz`` every 50 ms; latencies to ``out``."""
    probes = []
    t0 = time.perf_counter()
    with httpx.Client(base_url=url, timeout=60) as client:
        while time.perf_counter() - t0 < duration_s:
            start = time.perf_counter()
            client.get("/healthz")
            probes.append(time.perf_counter() - start)
            time.sleep(0.05)
    out.put(probes)


async def probes_under_big_bodies(url: str, clients: int, duration_s: float) -> dict[str, Any]:
    """``clients`` clients keep posting ≈ 3 MB plan bodies (an inline 1000 × 1000 grid, refused after parsing for
    its cells) while a separate process times ``GET /healthz`` every 50 ms."""
    import multiprocessing

    grid = {"data": [[0] * 1000 for _ in range(1000)], "resolution_m": 0.05}
    body = json.dumps({"map": grid, "start": {"x": 1, "y": 1, "yaw": 0}, "goal": {"x": 2, "y": 1, "yaw": 0}}).encode()
    statuses: dict[int, int] = {}
    ctx = multiprocessing.get_context("spawn")
    out = ctx.Queue()
    t0 = time.perf_counter()
    async with httpx.AsyncClient(base_url=url, timeout=180) as client:

        async def sender() -> None:
            while time.perf_counter() - t0 < duration_s:
                response = await client.post("/v1/plan", content=body, headers=JSON)
                statuses[response.status_code] = statuses.get(response.status_code, 0) + 1

        prober = ctx.Process(target=_probe_healthz, args=(url, duration_s, out))
        prober.start()
        await asyncio.gather(*(sender() for _ in range(clients)))
        probes: list[float] = await asyncio.to_thread(out.get, True, 120)
        prober.join(timeout=60)
    return {"probes": len(probes), "p50_ms": 1000 * _percentile(probes, 50), "p99_ms": 1000 * _percentile(probes, 99),
            "max_ms": 1000 * max(probes, default=float("nan")), "bodies": statuses, "body_mb": len(body) / 1e6}


def fleet_main(duration_s: float = 10.0, workers: int = 1, clients: tuple[int, ...] = (1, 4, 16)) -> int:
    """``sphereplan bench --suite load``: one instance vs two behind HAProxy, failover, probes under big bodies."""
    from lab.fleet import Fleet

    bodies = problem_requests(False)
    print(f"{len(bodies)} shipped problems round-robin, {duration_s:g} s per row, {workers} worker(s) per instance, "
          f"{os.cpu_count()} CPUs; load average 1/5 min at the end of each row\n")
    print(f"{'target':>26} {'clients':>7} {'requests':>8} {'req/s':>7} {'p50 ms':>8} {'p99 ms':>8} {'load':>9}"
          "  statuses")
    with tempfile.TemporaryDirectory(prefix="sphereplan-load-") as tmp:
        fleet = Fleet(Path(tmp))
        try:
            cap = ("--max-in-flight", str(4 * max(clients)))
            instances = [fleet.instance(f"p{i}", REPO / "maps", workers=workers, extra=cap) for i in range(2)]
            for instance in instances:
                fleet.wait_ready(instance)
            balancer = fleet.haproxy(instances)
            fleet.wait_ready(balancer)
            for name, url in (("one instance", instances[0].url), ("two behind HAProxy", balancer.url)):
                for n in clients:
                    r = asyncio.run(_safe_load(url, bodies, n, duration_s))
                    print(f"{name:>26} {n:>7} {r['requests']:>8} {r['rps']:>7.2f} {r['p50_ms']:>8.0f} "
                          f"{r['p99_ms']:>8.0f} {_load_avg():>9}  {dict(sorted(r['statuses'].items()))}"
                          + (f" transport errors {r['errors']}" if r["errors"] else ""), flush=True)
            h = asyncio.run(probes_under_big_bodies(instances[0].url, 16, duration_s))
            print(f"\nGET /healthz while 16 clients send {h['body_mb']:.1f} MB bodies to one instance: {h['probes']} "
                  f"probes, p50 {h['p50_ms']:.1f} ms, p99 {h['p99_ms']:.1f} ms, max {h['max_ms']:.1f} ms "
                  f"(load {_load_avg()}); bodies answered {dict(sorted(h['bodies'].items()))}", flush=True)
            f = asyncio.run(failover_run(balancer.url, bodies, 4, max(duration_s, 15.0), instances[0].kill))
            print(f"\nfailover: 4 clients through HAProxy, instance p1 SIGKILLed a third of the way in: {f['sent']} "
                  f"requests sent, {f['lost']} lost (transport errors), "
                  f"answered {dict(sorted(f['statuses'].items()))}; "
                  f"latency of requests around the kill p99 {f['p99_around_kill_ms']:.0f} ms, "
                  f"max {f['max_around_kill_ms']:.0f} ms (load {_load_avg()})")
        finally:
            fleet.close()
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m lab.loadtest", description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=10.0, help="seconds of load per worker count (10)")
    parser.add_argument("--concurrency", type=int, default=4, help="concurrent HTTP clients (4)")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="worker counts to test (1 2)")
    parser.add_argument("--zenoh-queries", type=int, default=20, help="sequential round trips to time (20)")
    parser.add_argument("--all", action="store_true", help="include the unsolvable problems (they time out)")
    parser.add_argument("--fleet", action="store_true",
                        help="the fleet suite instead (sphereplan bench --suite load): 1/4/16 clients against one "
                             "instance and two behind HAProxy, health probes under big bodies, failover")
    args = parser.parse_args(argv)
    if args.fleet:
        return fleet_main(args.duration, args.workers[0])
    bodies = problem_requests(args.all)
    print(f"{len(bodies)} shipped problems, {args.concurrency} concurrent clients, {args.duration:g} s per run, "
          f"{os.cpu_count()} CPUs\n")
    print(f"{'workers':>7} {'start s':>8} {'requests':>8} {'req/s':>7} {'p50 ms':>8} {'p99 ms':>8} "
          f"{'plan ms':>8}  statuses   (plan ms: mean planning_time_s the workers report)")
    served_last = None
    for workers in args.workers:
        with serve(workers, max_in_flight=max(4 * workers, args.concurrency)) as served:
            r = asyncio.run(http_load(served.url, bodies, args.concurrency, args.duration))
            print(f"{workers:>7} {served.startup_s:>8.1f} {r['requests']:>8} {r['rps']:>7.2f} {r['p50_ms']:>8.0f} "
                  f"{r['p99_ms']:>8.0f} {r['plan_ms']:>8.0f}  {dict(sorted(r['statuses'].items()))}", flush=True)
            if workers == args.workers[-1]:
                served_last = round_trips(served, bodies[0], args.zenoh_queries)
    if served_last:
        print(f"\nsequential round trips ({args.zenoh_queries} each, problem {bodies[0]['map']} "
              f"{bodies[0]['start']} -> {bodies[0]['goal']}):")
        print(f"{'':48} {'p50 ms':>8} {'p99 ms':>8} {'mean ms':>8}")
        for name, times in served_last.items():
            print(f"{name:48} {1000 * _percentile(times, 50):>8.1f} {1000 * _percentile(times, 99):>8.1f} "
                  f"{1000 * statistics.fmean(times):>8.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
