"""Loss on one link, a healthy robot beside it: ``python -m benchmarks.link_loss``.

Carry-bar with three robots (6.3.2 with a third): Pippi carries the bar and
coordinates, Emil and Rasmus can each help her (each has a laser; the
cheapest configuration uses Emil). Pippi and Rasmus share one network
namespace, a healthy link between them; Emil sits in another, behind the
lossy link of :mod:`benchmarks.lossy_link` (a forwarder between two TUN
devices that drops a seeded share of the packets: TCP sees real loss). After
the goal is served, Emil's link loses ``--loss`` of its packets for
``--seconds``; then it heals. Emil is lost, and the goal should go on with
Rasmus; Rasmus, on the healthy link, should never be lost.

Each topology runs ``--trials`` times, side by side:

* *router* — ``cfgplan launch``'s default: every robot a client of one Zenoh
  router (``cfgplan router``) in Pippi's namespace;
* *mesh* — every robot a peer linked to every other (``--topology mesh``).

The table counts the trials in which Pippi lost Rasmus (``robot-lost`` or a
failure of him), the longest time the goal stood still (a
``no-configuration`` to the next switch), the trials in which Emil was lost
(the loss bit), and the share of the loss's cycles in which Pippi's action
ran. ``--markdown FILE`` writes the documentation's page
(``docs/explanation/link-loss.md``). Needs root, ``ip`` (iproute2) and
``/dev/net/tun``; every process is stopped by its pid and the namespaces are
deleted.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import shlex
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.fault_conditions import Record, read_trace
from benchmarks.lossy_link import LinkUnavailable, NetnsLink
from benchmarks.page import revision
from benchmarks.reconfigure import ROOT, table
from benchmarks.run import machine

DOMAIN = ROOT / "domains" / "carry-bar" / "domain.lisp"
STATE = """\
(state robot(Pippi), robot(Emil), robot(Rasmus), sonar(Pippi), sonar(Emil), sonar(Rasmus),
       odometer(Pippi), odometer(Emil), odometer(Rasmus), laser(Emil), laser(Rasmus),
       in(Pippi, Room1), in(Emil, Room1), in(Rasmus, Room1))
(goal (do-carry-bar Pippi))
"""
HERMETIC = "{ scouting: { multicast: { enabled: false }, gossip: { enabled: false } } }"
TOPOLOGIES = ("router", "mesh")
PORT = 7447  # inside the namespaces: nobody else listens there
SIDES = {"Pippi": 0, "Rasmus": 0, "Emil": 1}
GOAL = "lead-robot"  # Pippi's action


@dataclass(frozen=True)
class Options:
    """Tuning of the benchmark."""

    trials: int = 3
    loss: float = 0.5
    seconds: float = 30.0  # how long the loss lasts
    settle: float = 3.0  # seconds of service before the loss
    startup: float = 90.0  # bound on the first service
    watch: float = 20.0  # bound on the service again after the link heals
    seed: int = 57
    zenoh_log: str | None = None  # Zenoh's log level in every process (its RUST_LOG)


LOGGED = (
    "import sys, zenoh; zenoh.init_log_from_env_or(sys.argv.pop(1)); "
    "sys.argv[0] = 'cfgplan'; from cfgplan.cli.app import console; console()"
)
"""``python -m cfgplan`` with Zenoh's log on (the level its first argument)."""


@dataclass
class Trial:
    """What one trial saw in Pippi's trace."""

    healthy_lost: bool = False
    lossy_lost: bool = False
    stopped: float = 0.0  # the longest no-configuration, seconds
    served: float = 0.0  # share of the loss's cycles in which the goal ran
    events: list[str] = field(default_factory=list)  # Pippi's, from the loss on


def network(topology: str, link: NetnsLink) -> dict[str, list[str]]:
    """Each robot's network options: clients of a router in Pippi's namespace,
    or (``mesh``) peers each linked to every other, as launch starts them."""
    here, there = link.addresses
    if topology == "router":
        return {r: ["--router", f"tcp/{here}:{PORT}"] for r in SIDES}
    pippi, rasmus, emil = f"tcp/{here}:{PORT}", f"tcp/{here}:{PORT + 1}", f"tcp/{there}:{PORT}"
    return {
        "Pippi": ["--listen", pippi],
        "Rasmus": ["--listen", rasmus, "--connect", pippi],
        "Emil": ["--listen", emil, "--connect", pippi, "--connect", rasmus],
    }


def about(record: Record, robot: str) -> bool:
    """A loss of ``robot``: its ``robot-lost``, or a failure of it."""
    return (record["event"] == "robot-lost" and record.get("other") == robot) or (
        record["event"] == "failure" and record.get("resource") == robot
    )


def _t(record: Record) -> float:
    return float(record["t"])  # type: ignore[arg-type]


def _ran(trace: Path, after: float) -> Record | None:
    for r in read_trace(trace):
        if (
            r["event"] == "call"
            and r.get("functionality") == GOAL
            and r.get("status") == "ran"
            and _t(r) > after
        ):
            return r
    return None


def _until(found: object, limit: float) -> Record | None:
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline:
        got = found()  # type: ignore[operator]
        if got is not None:
            return got  # type: ignore[no-any-return]
        time.sleep(0.05)
    return None


def run_trial(
    topology: str, options: Options, link: NetnsLink, folder: Path, code: Path = ROOT
) -> Trial:
    """One trial (see the module's docstring), the robots and the router
    running the ``cfgplan`` of the checkout ``code``."""
    config, state, impl = folder / "zenoh.json5", folder / "state.lisp", folder / "impl.py"
    config.write_text(HERMETIC)
    state.write_text(STATE)
    example = (ROOT / "examples" / "carry-bar" / "impl.py").read_text("utf-8")
    impl.write_text(f'{example}\nWORLD["Rasmus"] = (3.5, 4.0, 0.0)\n')
    traces = {r: folder / f"{r.lower()}.jsonl" for r in SIDES}
    common = ["--impl", str(impl), "--zenoh-config", str(config), "--society", "link-loss"]
    bound = options.startup + options.settle + options.seconds + options.watch + 30
    common += ["--rate", "10", "--duration", f"{bound:g}"]
    started: list[subprocess.Popen[bytes]] = []

    def start(side: int, args: list[str], name: str) -> None:
        with open(folder / f"{name}.log", "wb") as log:
            program = ["-m", "cfgplan"]
            if options.zenoh_log is not None:
                program = ["-c", LOGGED, options.zenoh_log]
            command = link.wrap(side, [sys.executable, *program, *args])
            env = {k: v for k, v in os.environ.items() if k != "ZENOH_RUNTIME"}  # each its own
            started.append(
                subprocess.Popen(command, cwd=code, env=env, stdout=log, stderr=subprocess.STDOUT)
            )

    try:
        if topology == "router":
            start(0, ["router", "--listen", f"tcp/{link.addresses[0]}:{PORT}"], "router")
        for robot, extra in network(topology, link).items():
            args = ["run", str(DOMAIN), str(state), "--robot", robot, *common, *extra]
            start(SIDES[robot], [*args, "--trace", str(traces[robot])], robot)
        if _until(lambda: _ran(traces["Pippi"], 0.0), options.startup) is None:
            raise RuntimeError(f"{GOAL} never ran within {options.startup:g} s")
        time.sleep(options.settle)
        began = time.time()
        link.set(loss=options.loss)
        time.sleep(options.seconds)
        link.set()
        healed = time.time()
        _until(lambda: _ran(traces["Pippi"], healed), options.watch)
    finally:
        link.set()
        for process in started:
            with contextlib.suppress(ProcessLookupError):
                os.kill(process.pid, signal.SIGTERM)
        for process in started:
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(10)
    return measure(read_trace(traces["Pippi"]), began, healed)


def measure(pippi: list[Record], began: float, healed: float) -> Trial:
    """The trial's figures from Pippi's trace; the loss lasted ``began`` to ``healed``."""
    trial = Trial()
    trial.healthy_lost = any(about(r, "Rasmus") for r in pippi)
    trial.lossy_lost = any(about(r, "Emil") for r in pippi)
    stop: float | None = None
    for r in pippi:
        if r["event"] == "no-configuration" and stop is None:
            stop = _t(r)
        elif r["event"] == "switch" and stop is not None:
            trial.stopped = max(trial.stopped, _t(r) - stop)
            stop = None
    if stop is not None and pippi:
        trial.stopped = max(trial.stopped, _t(pippi[-1]) - stop)
    ran = sum(
        1
        for r in pippi
        if r["event"] == "call"
        and r.get("functionality") == GOAL
        and r.get("status") == "ran"
        and began <= _t(r) <= healed
    )
    trial.served = ran / max(1.0, 10 * (healed - began))
    for r in pippi:
        if _t(r) >= began - 0.5 and r["event"] in ("robot-lost", "no-configuration", "switch"):
            what = r.get("other") or r.get("cause") or ""
            trial.events.append(f"+{_t(r) - began:.2f}s {r['event']} {what}")
    return trial


HEADER = [
    "topology",
    "trials",
    "healthy Rasmus lost",
    "goal stopped, longest",
    "lossy Emil lost",
    "served during loss",
]


def row(topology: str, trials: list[Trial]) -> list[str]:
    n = len(trials)
    served = statistics.median(t.served for t in trials) if trials else 0.0
    return [
        topology,
        str(n),
        f"{sum(t.healthy_lost for t in trials)}/{n}",
        f"{max((t.stopped for t in trials), default=0.0):.1f} s",
        f"{sum(t.lossy_lost for t in trials)}/{n}",
        f"{100 * served:.0f} %",
    ]


INTRO = """\
`python -m benchmarks.link_loss` asks whether loss on one robot's link can
cost a robot on a healthy one. Carry-bar with a third robot: Pippi carries
the bar and coordinates; Emil and Rasmus can each help her (the cheapest
configuration uses Emil). Pippi and Rasmus share a network namespace (a
healthy link); Emil sits in another, behind a forwarder between two TUN
devices that drops {loss:.0%} of the packets for {seconds:g} s, then heals.
Emil is lost and the goal should go on with Rasmus; Rasmus should never be
lost. Each topology runs {trials} times: *router*, launch's default (every
robot a client of one Zenoh router beside Pippi), and *mesh* (every robot
a peer linked to every other).{baseline}

Columns, from Pippi's trace: the trials in which she lost Rasmus (his
token went in her session, or his failure was recorded: a loss she held
and let go counts too), the longest time her goal stood still (no
configuration, until the next switch: what a loss taken cost), the trials
in which Emil was lost (the loss bit), and the share of the loss's cycles
in which her action ran (median).

## Why a healthy robot was lost

**A send that waits for a full link, on a healthy link's thread.** Zenoh
sends declarations (liveliness tokens, subscribers, interests) with
congestion control *block*: a send to a link whose queue (two batches per
priority) is full waits for room, up to
`transport/link/tx/queue/congestion_control/block/wait_before_close` (5 s
by default), and only then closes that link. The wait is on the thread
that sends (`TransmissionPipelineProducer::push_network_message` in
`io/zenoh-transport/src/common/pipeline.rs`, Zenoh 1.9/1.10). In a router
that thread is the receive task of the link the declaration came on: its
`read_loop` (`io/zenoh-transport/src/unicast/universal/link.rs`) hands each
batch to the routing, which pushes into every other client's queue. While
the loss shuts Emil's TCP window his queue fills, and the next declaration
from Pippi or Rasmus (a switch declares publishers and subscribers) holds
that healthy link unread for up to 5 s, past its 2 s lease; when the task
runs again, `read_loop`'s `select!` finds both a batch to read and the
lease run out, and takes one at random: the router drops the healthy client
(`RX task failed: ... expired after 2000 milliseconds` in its debug log) in
about half such stalls, and everyone sees it lost. A slow test
(`tests/runtime/test_stuck_link.py`: a client on a link that drops every
packet, which the router keeps, and a healthy one beside it) shows it
alone: with Zenoh's 5 s the healthy client's beat stopped 5.6 s and the
router dropped it; with cfgplan's setting the longest gap is 0.13 s.
cfgplan now sets `wait_before_close` to a twentieth of the lease (100 ms
with the 2 s lease) for `cfgplan router` and for every robot, unless a
`--zenoh-config` file sets it: a link that cannot take a control message
for that long is closed, and its robot is lost, as it would be anyway.

**A second stall: a socket closed on the thread that reads the others.**
Zenoh sets `SO_LINGER` to 10 s on every TCP link (`LinkUnicastTcp::new`
in `io/zenoh-links/zenoh-link-tcp/src/unicast.rs`, `TCP_LINGER_TIMEOUT`
in its `lib.rs`; a build-time constant, with `#[allow(deprecated)]` over
tokio's `set_linger`, deprecated because it makes a drop block). With it,
`close(2)` of a socket whose FIN (or last bytes) the other end has not
acknowledged blocks the calling thread in the kernel until they are, or
10 s, non-blocking socket or not. A handshake with Emil that fails (his
`open_timeout` runs out and he hangs up: `Read error ... early eof`; or
the router's `accept_timeout`) ends in `accept_link`
(`io/zenoh-transport/src/unicast/establishment/accept.rs`), a task on
Zenoh's *acceptor* runtime (`handle_new_link_unicast` in
`unicast/manager.rs`), which drops the socket there; its FIN crosses the
lossy link and is lost, and the thread waits. That runtime has one thread
by default, and the listener's accept loop runs on it too, so every
socket it accepted (the healthy clients' as well) is registered with its
I/O driver: while that thread sits in `close(2)`, no readiness reaches
any receive task, the router reads no client and accepts no new one, and
past the lease drops them all. No lock is involved (the routing tables'
locks are taken and let go before any network wait in
`new_transport_unicast`). Sampling the router's threads' kernel wait
(`/proc/PID/task/*/wchan`) every 20 ms in a small harness (a router, two
healthy clients beating at 50 Hz, a third behind the 50 % loss for 30 s)
shows it: in the trials where both healthy clients were dropped, the
thread `acc-0` sat in `wait_woken` for 10.1, 13.8 and 6.9 s, and the
healthy clients' longest silence was 10.1, 14.1 and 6.9 s. The same close
on a receive thread (`rx-*`, when Emil's established link is dropped) was
seen holding one for 10 s as well.

**What cfgplan does about that one.** No Zenoh setting removes the
linger. cfgplan starts Zenoh with spare threads (`ZENOH_RUNTIME` set to
8 acceptor threads and 4 receive threads, unless it is set already) for
`cfgplan router` and every robot. It shortens the stall but does not end
it: the spare threads sleep until something wakes one (tokio's I/O
driver is taken over only by a thread that goes idle), and the first
thing that does is the router's own lease closing the silent links. A
slow test (`tests/runtime/test_stuck_handshake.py`: a TCP connection to
the router that says nothing, then a cut link, so the router's FIN after
its `accept_timeout` is never acknowledged) measures it: with one
acceptor thread the healthy clients' beat stopped for the whole 10 s
linger; with the spare threads for 1.8 s, and they are still dropped
once. So the table's count of healthy robots lost is not expected to fall
(the stall still outlasts the lease); how long they stay away is. The fix
belongs in Zenoh (no `SO_LINGER` on an async socket, or the close on a
blocking thread), whose maintainers have it open as
[Zenoh should not use deprecated `set_linger`](https://github.com/eclipse-zenoh/zenoh/issues/2350),
after tokio deprecated `set_linger` for this very block; until then the
hold below covers the coordinator in a router's society.

**What cfgplan does about it.** A robot that is a client of a router now
knows when its *own* link to the router is gone (Zenoh closes the link
before it tells the liveliness subscribers; its transport listener says
so a moment later), and the coordinator then holds every loss it sees, as
after its own stall, for as long as the cut lasts and two leases more: a
robot seen again by the same process is let go, one still gone is taken.
The goal cannot be served while the router does not route (the last
column), but the coordinator no longer blames a healthy robot for it, nor
stops everything when he comes back (`tests/reconfigure/test_network_freeze.py`
freezes the router 3 s: before, the coordinator recorded its helper's
failure; now none).

**In a mesh** each peer gets the same `wait_before_close`, but the hold does
not apply: a peer's link that closes is the loss of the robot at its other
end, and nothing tells it from a stall of the link. There the healthy link
between Pippi and Rasmus still went in some trials, both seeing the other
lost at the same moment and back only seconds later: the second stall, in
a peer's session (a peer accepts links too, and Pippi accepted both
Rasmus's and Emil's). What is left: the linger in Zenoh, and in a mesh,
judging a robot's liveliness over a second path (its data still arriving,
or a peer that still hears it) before a loss is taken.
"""


PAGE = """\
<!-- Written by `{shown}`: do not edit by hand. -->

# Loss on one link

{intro}
## The last run

{facts}

{table}

{evidence}Made with `{shown}`; run it again to regenerate this page. What the
figures mean, and what is left, is on the [faults page](faults.md).
"""


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.link_loss", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--trials", type=int, default=3, help="trials per topology (3)")
    parser.add_argument("--seconds", type=float, default=30.0, help="the loss lasts (30)")
    parser.add_argument("--loss", type=float, default=0.5, help="share of packets dropped (0.5)")
    parser.add_argument("--topology", action="append", choices=TOPOLOGIES, help="default: both")
    parser.add_argument("--seed", type=int, default=57, help="the link's dropped packets (57)")
    parser.add_argument(
        "--baseline",
        type=Path,
        help="also run every trial with the cfgplan of this checkout (e.g. from git archive), "
        "alternating with this one's",
    )
    parser.add_argument(
        "--zenoh-log", metavar="LEVEL", help="Zenoh's log in each process's log (e.g. debug)"
    )
    parser.add_argument("--keep", type=Path, help="keep each trial's logs and traces here")
    parser.add_argument("--markdown", type=Path, help="also write the documentation page here")
    parser.add_argument(
        "--rewrite",
        type=Path,
        metavar="PAGE",
        help="write PAGE again in this module's words, its run kept (nothing is measured)",
    )
    return parser


def _intro(args: argparse.Namespace) -> str:
    """The page's words before its run, for the command's ``args``."""
    baseline = (
        ""
        if args.baseline is None
        else " Each trial runs twice in turn: with this checkout's cfgplan (*this*), and "
        f"with the one in `{args.baseline.name}`, the baseline (`git archive REV | tar -x -C "
        "DIR` of the code before)."
    )
    return INTRO.format(loss=args.loss, seconds=args.seconds, trials=args.trials, baseline=baseline)


def rewrite(page: Path) -> None:
    """Write ``page`` again with this module's words; its run (facts, table,
    evidence) and the command that made it kept as they are."""
    text = page.read_text(encoding="utf-8")
    made = re.search(r"^Made with `python -m benchmarks\.link_loss ?(.*?)`;", text, re.M)
    run = text.split("## The last run\n", 1)
    if made is None or len(run) != 2:
        raise SystemExit(f"{page}: not a page benchmarks.link_loss wrote")
    args = _parser().parse_args(shlex.split(made.group(1)))
    shown = shlex.join(["python", "-m", "benchmarks.link_loss", *shlex.split(made.group(1))])
    head = f"<!-- Written by `{shown}`: do not edit by hand. -->\n\n# Loss on one link\n\n"
    page.write_text(f"{head}{_intro(args)}\n## The last run\n{run[1]}", encoding="utf-8")


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.rewrite is not None:
        rewrite(args.rewrite)
        print(f"wrote {args.rewrite}")
        return 0
    options = Options(
        trials=args.trials,
        loss=args.loss,
        seconds=args.seconds,
        seed=args.seed,
        zenoh_log=args.zenoh_log,
    )
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    try:
        link = NetnsLink(seed=options.seed)
    except LinkUnavailable as error:
        print(f"error: {error} (sudo apt-get install -y iproute2; run as root)", file=sys.stderr)
        return 1
    load, started = os.getloadavg()[0], time.monotonic()
    rows, evidence = [], []
    codes = {"": ROOT}
    if args.baseline is not None:
        codes = {" (this)": ROOT, f" ({args.baseline.name})": args.baseline}
    try:
        for topology in args.topology or TOPOLOGIES:
            trials: dict[str, list[Trial]] = {label: [] for label in codes}
            for k in range(options.trials):
                for label, code in codes.items():  # side by side, in turn
                    with tempfile.TemporaryDirectory(prefix="cfgplan-link-loss-") as name:
                        trial = run_trial(topology, options, link, Path(name), code)
                        if args.keep is not None:
                            kept = args.keep / f"{topology}-{code.name}-{k + 1}"
                            shutil.copytree(name, kept, dirs_exist_ok=True)
                    trials[label].append(trial)
                    shown = f"{topology}{label}"
                    print(f"{shown} #{k + 1}: {row(shown, [trial])}", file=sys.stderr)
                    if trial.healthy_lost:
                        evidence.append(f"- {shown}, trial {k + 1}:")
                        evidence += [f"    {e}" for e in trial.events]
            rows += [row(f"{topology}{label}", trials[label]) for label in codes]
    finally:
        link.close()
    facts = [
        f"- machine: {machine()}",
        f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
        f"- revision: `{revision()}`",
        f"- link: {link.kind}; loss seed {options.seed}",
        f"- load average (1 min) before / after: {load:.2f} / {os.getloadavg()[0]:.2f}; "
        f"{time.monotonic() - started:.0f} s in all",
    ]
    lines = table(HEADER, rows)
    print("\n".join([*facts, "", lines]))
    if evidence:
        print("\nTrials in which Rasmus was lost (Pippi's events from the loss on):")
        print("\n".join(evidence))
    if args.markdown:
        given = sys.argv[1:] if argv is None else argv
        shown = shlex.join(["python", "-m", "benchmarks.link_loss", *given])
        heading = "### Trials in which Rasmus was lost: Pippi's events from the loss on"
        over = "\n".join([heading, "", "```text", *evidence, "```", "", ""]) if evidence else ""
        text = PAGE.format(
            shown=shown, intro=_intro(args), facts="\n".join(facts), table=lines, evidence=over
        )
        args.markdown.write_text(text, encoding="utf-8")
        print(f"\nwrote {args.markdown}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
