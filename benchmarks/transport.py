"""A global channel over Zenoh beside the in-process transport: ``python -m benchmarks.transport``.

Prints one table, both transports measured in the same run on the same
machine. What is timed is the runtime's own path — ``Channel.write`` (value
rule, JSON envelope) through the transport to the other end's
``Channel.receive`` — not Zenoh alone:

* **round trip**: robot A writes a value on a global channel to B; B, polling,
  reads it and writes it back on a channel to A; A polls until it arrives.
  Median and 99th percentile over ``--round-trips``.
* **throughput**: A writes ``--messages`` values back to back; the rate A
  sustains, and the rate at which B's one-slot end sees *new* values (a
  one-slot channel keeps only the newest: what B misses was overwritten, by
  design, 5.2.2).

In process both ends are in one interpreter and a send is delivered at once.
Over Zenoh, B is a second process (``--echo``) on loopback, peers connected by
explicit endpoints on free ports, scouting off. Two payloads: a pose (two
floats) and a 1000-float scan.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from cfgplan.runtime import Channel, InProcessTransport, Transport, make_global_channel
from cfgplan.runtime.spawn import free_port
from cfgplan.runtime.zenoh_transport import ZenohOptions, ZenohTransport

ROOT = Path(__file__).resolve().parents[1]
HERMETIC = "{ scouting: { multicast: { enabled: false }, gossip: { enabled: false } } }"
SOCIETY = "cfgplan-benchmark"
PAYLOADS: dict[str, object] = {"pose": (0.695, -2.601), "scan 1000 floats": [0.5] * 1000}
STOP = "stop"
TIME_LIMIT = 60.0  # seconds for any one wait


def ends(transport: Transport, me: str, other: str) -> tuple[Channel, Channel, Channel]:
    """``me``'s ends: out to ``other``, back from it, and the throughput channel in."""
    out = make_global_channel(other, "F1", "F2", ("ping",), robot=me, transport=transport)
    back = make_global_channel(other, "F3", "F4", ("pong",), robot=me, transport=transport)
    flood = make_global_channel(other, "F5", "F6", ("flood",), robot=me, transport=transport)
    return out, back, flood


def wait_fresh(channel: Channel, poll: Callable[[], None], limit: float = TIME_LIMIT) -> object:
    deadline = time.monotonic() + limit
    while not channel.fresh:
        poll()
        if time.monotonic() > deadline:
            raise SystemExit(f"benchmark: nothing arrived within {limit:g} s")
    return channel.read()


def round_trips(
    send: Channel, receive: Channel, poll: Callable[[], None], value: object, n: int
) -> list[float]:
    times = []
    for i in range(n):
        started = time.perf_counter()
        send.write([i, value])
        wait_fresh(receive, poll)
        times.append(time.perf_counter() - started)
    return times


def in_process(value: object, n: int, messages: int) -> tuple[list[float], float, float]:
    transport = InProcessTransport()
    a_out, a_back, a_flood = ends(transport, "A", "B")
    b_in, b_back, b_flood = ends(transport, "B", "A")

    def poll() -> None:  # B echoes whatever arrived
        if b_in.fresh:
            b_back.write(b_in.read())

    times = round_trips(a_out, a_back, poll, value, n)
    seen = 0
    started = time.perf_counter()
    for i in range(messages):
        a_flood.write([i, value])
        if b_flood.fresh:
            b_flood.read()
            seen += 1
    elapsed = time.perf_counter() - started
    return times, messages / elapsed, seen / elapsed


def over_zenoh(
    value: object, n: int, messages: int, config: str
) -> tuple[list[float], float, float]:
    b_port, a_port = free_port(), free_port()
    echo = subprocess.Popen(
        [sys.executable, "-m", "benchmarks.transport", "--echo", str(b_port), config],
        cwd=ROOT,
    )
    try:
        options = ZenohOptions(
            society=SOCIETY,
            listen=(f"tcp/127.0.0.1:{a_port}",),
            connect=(f"tcp/127.0.0.1:{b_port}",),
            config_file=config,
        )
        transport = ZenohTransport("A", options)
        a_out, a_back, a_flood = ends(transport, "A", "B")
        deadline = time.monotonic() + TIME_LIMIT
        while not a_back.fresh:  # until B is up and both subscriptions are known
            a_out.write(["hello", None])
            transport.poll()
            time.sleep(0.01)
            if time.monotonic() > deadline:
                raise SystemExit("benchmark: the echo process did not answer")
        a_back.read()

        def poll() -> None:  # sleep until something arrives, as a robot would
            transport.wait(TIME_LIMIT)
            transport.poll()

        round_trips(a_out, a_back, poll, value, max(10, n // 10))  # warm up
        times = round_trips(a_out, a_back, poll, value, n)
        started = time.perf_counter()
        for i in range(messages):
            a_flood.write([i, value])
        elapsed = time.perf_counter() - started
        a_out.write([STOP, elapsed])
        seen = wait_fresh(a_back, poll)
        assert isinstance(seen, int)
        transport.close()
        echo.wait(timeout=TIME_LIMIT)
        return times, messages / elapsed, seen / elapsed
    finally:
        if echo.poll() is None:
            os.kill(echo.pid, signal.SIGKILL)
            echo.wait(timeout=TIME_LIMIT)


def echo(port: int, config: str) -> None:
    """Robot B: answer each ping, count what the flood channel shows, stop on ``stop``."""
    options = ZenohOptions(society=SOCIETY, listen=(f"tcp/127.0.0.1:{port}",), config_file=config)
    transport = ZenohTransport("B", options)
    b_in, b_back, b_flood = ends(transport, "B", "A")
    seen = 0
    deadline = time.monotonic() + 10 * TIME_LIMIT
    while time.monotonic() < deadline:
        transport.wait(1.0)
        transport.poll()
        if b_flood.fresh:
            b_flood.read()
            seen += 1
        if b_in.fresh:
            got = b_in.read()
            if isinstance(got, list) and got and got[0] == STOP:
                b_back.write(seen)
                time.sleep(0.2)  # let the answer leave before the session closes
                break
            b_back.write(got)
    transport.close()


def _us(seconds: float) -> str:
    return f"{seconds * 1e6:,.0f}"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description="Round trip and throughput of a global channel.")
    parser.add_argument("--round-trips", type=int, default=2000)
    parser.add_argument("--messages", type=int, default=20000)
    parser.add_argument("--echo", nargs=2, metavar=("PORT", "CONFIG"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.echo:
        echo(int(args.echo[0]), args.echo[1])
        return
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        config = str(Path(folder) / "zenoh.json5")
        Path(config).write_text(HERMETIC)
        for name, value in PAYLOADS.items():
            size = len(json.dumps(value))
            local = in_process(value, args.round_trips, args.messages)
            remote = over_zenoh(value, args.round_trips, args.messages, config)
            rows.append((name, size, local, remote))
    print(
        f"- machine: {platform.system()} {platform.machine()}, {os.cpu_count()} cores; "
        f"Python {platform.python_version()}"
    )
    print(
        f"- {args.round_trips} round trips, {args.messages} messages per payload; "
        "Zenoh: two processes on loopback"
    )
    print()
    print(
        "| payload | transport | round trip median µs | p99 µs | writes/s | new values seen/s |"
        " round trip / in-process | values seen / in-process |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name, size, local, remote in rows:
        base, base_seen = statistics.median(local[0]), local[2]
        for label, (times, sent, seen) in (("in-process", local), ("Zenoh", remote)):
            median = statistics.median(times)
            p99 = statistics.quantiles(times, n=100)[98]
            print(
                f"| {name} ({size} B) | {label} | {_us(median)} | {_us(p99)} | {sent:,.0f} | "
                f"{seen:,.0f} | {median / base:.1f}x | {seen / base_seen:.2f}x |"
            )


if __name__ == "__main__":
    main()
