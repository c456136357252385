"""Messages sent in bursts, how many arrive: ``python -m benchmarks.bursts``.

The switch protocol's messages go out in bursts: the last commit of a
sequence, the state the society committed and the finish leave the
coordinator within a millisecond of each other. Zenoh's puts default to
congestion control *drop*: a message its link's queue cannot take at once is
dropped, not waited for. On a loaded machine, where the thread that drains the
queue waits for a core, some of a burst are lost; that is why the coordinator
tells a prepare, a commit and the finish again to the robots that have not
answered them (docs/explanation/switch-protocol.md, "A message lost on the
way"), instead of sending with *block*, which would stall its loop on a stuck
link.

One table, both modes measured in the same run, in turn: a receiver (a
second process, a Zenoh peer with cfgplan's session settings on a free
loopback port, scouting off) counts what arrives of ``--bursts`` bursts of
three 150-byte messages, 20 ms apart, sent by this process as a peer that
connects to it. Run it beside other work (``--busy N`` starts N busy loops
for the run, stopped by their pids) to see the loss a loaded machine makes.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager

from benchmarks.run import machine
from cfgplan.runtime.spawn import free_port
from cfgplan.runtime.zenoh_config import ZenohOptions, zenoh_config

KEY = "cfgplan-bench/bursts"
SIZE = 150  # bytes: about a commit's JSON
GAP = 0.02  # seconds between bursts
WAIT = 30.0  # seconds any step may take


def receive(endpoint: str, seconds: float) -> None:
    """The receiver (``--receive``): count the messages on :data:`KEY` for
    ``seconds`` after saying ``ready``, then print the count."""
    import zenoh

    session = zenoh.open(zenoh_config(ZenohOptions(listen=(endpoint,))))
    got = [0]

    def count(_sample: object) -> None:
        got[0] += 1

    subscriber = session.declare_subscriber(KEY, count)
    print("ready", flush=True)
    time.sleep(seconds)
    print(got[0], flush=True)
    subscriber.undeclare()  # type: ignore[no-untyped-call]
    session.close()  # type: ignore[no-untyped-call]


def send(endpoint: str, bursts: int, block: bool) -> int:
    """Send ``bursts`` bursts of three to a receiver on ``endpoint``; how many arrived."""
    import zenoh

    seconds = 2.0 + bursts * GAP + 2.0
    receiver = subprocess.Popen(
        [sys.executable, "-m", "benchmarks.bursts", "--receive", endpoint, f"{seconds:g}"],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert receiver.stdout is not None
        if receiver.stdout.readline().strip() != "ready":
            raise SystemExit("the receiver did not start")
        session = zenoh.open(zenoh_config(ZenohOptions(connect=(endpoint,))))
        control = zenoh.CongestionControl.BLOCK if block else zenoh.CongestionControl.DROP
        publisher = session.declare_publisher(KEY, express=True, congestion_control=control)
        time.sleep(1.0)  # the receiver's subscriber known
        payload = b"x" * SIZE
        for _ in range(bursts):
            for _ in range(3):
                publisher.put(payload)
            time.sleep(GAP)
        publisher.undeclare()  # type: ignore[no-untyped-call]
        out, _ = receiver.communicate(timeout=seconds + WAIT)
        session.close()  # type: ignore[no-untyped-call]
        return int(out.split()[-1])
    finally:
        if receiver.poll() is None:
            os.kill(receiver.pid, signal.SIGKILL)
            receiver.wait(WAIT)


@contextmanager
def busy(loops: int) -> Iterator[None]:
    """``loops`` processes that spin for the block, stopped by their pids."""
    spinning = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(loops)]
    try:
        yield
    finally:
        for process in spinning:
            os.kill(process.pid, signal.SIGKILL)
            process.wait(WAIT)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--bursts", type=int, default=400, help="bursts of three per run")
    parser.add_argument("--rounds", type=int, default=3, help="runs of each mode, in turn")
    parser.add_argument("--busy", type=int, default=0, help="busy loops beside the run")
    parser.add_argument(
        "--receive", nargs=2, metavar=("ENDPOINT", "SECONDS"), help=argparse.SUPPRESS
    )
    args = parser.parse_args(argv)
    if args.receive:
        receive(args.receive[0], float(args.receive[1]))
        return
    arrived: dict[str, list[int]] = {"drop": [], "block": []}
    before = os.getloadavg()[0]
    with busy(args.busy):
        for _ in range(args.rounds):
            for mode in arrived:
                endpoint = f"tcp/127.0.0.1:{free_port()}"
                arrived[mode].append(send(endpoint, args.bursts, mode == "block"))
        after = os.getloadavg()[0]
    sent = 3 * args.bursts
    print(f"machine: {machine()}")
    print(
        f"load average (1 min) before / after: {before:.2f} / {after:.2f}; busy loops: {args.busy}"
    )
    print()
    print("| congestion control | runs | sent per run | arrived per run | lost, worst run |")
    print("|---|---|---|---|---|")
    for mode, counts in arrived.items():
        each = ", ".join(str(n) for n in counts)
        worst = max(sent - n for n in counts)
        print(f"| {mode} | {len(counts)} | {sent} | {each} | {worst} ({worst / sent:.1%}) |")


if __name__ == "__main__":
    main()
