"""Faults, measured: ``python -m benchmarks.faults`` prints how a society rides them out (5.5).

Each condition of :data:`benchmarks.fault_conditions.CONDITIONS` runs
``--trials`` times against real processes — one ``cfgplan run --robot`` per
robot over Zenoh — through the lossy link of :mod:`benchmarks.lossy_link`
(two network namespaces joined by a forwarder that drops and delays packets,
where the machine allows it; else a TCP proxy that cuts and delays, and the
loss rows are n/a). The table: detection, switch, recovery after the
condition cleared (min / median / max), spurious switches, permanent stops,
the share of cycles served during the fault, and ✓/✗ against the limit
hold + 1 s. ``--markdown FILE`` also writes the documentation's page
(``docs/explanation/faults.md``).
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import statistics
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.fault_conditions import CONDITIONS, Condition, Options, Trial, TrialError, run_trial
from benchmarks.lossy_link import Link, LinkUnavailable, NetnsLink, ProxyLink
from benchmarks.page import revision
from benchmarks.reconfigure import table
from benchmarks.run import machine
from cfgplan.runtime.spawn import free_port

HEADER = [
    "condition",
    "trials",
    "detection s",
    "switch s",
    "recovery s min / med / max",
    "spurious switches",
    "permanent stops",
    "served during fault",
    "≤ hold + 1 s",
]

INTRO = """\
`python -m benchmarks.faults` runs each condition below against real
processes: cross-door step 2 (6.2.2; Emil owns the goal and coordinates,
Pippi helps, every configuration needs her) and docking with Vacu's laser
failed (Vacu docks and coordinates, Robby's laser localizes him; the ceiling
camera CamKitchen once left out of the state, once declared but its process
not started), one `cfgplan run --robot` process per robot over Zenoh, as
peers (the helper connects to the coordinator) without the society's keys, at 20
cycles per second, lease {lease:g} s, hold {hold:g} s. The coordinator runs in one network
namespace and the helper in another; a forwarder in the benchmark's process
moves every IP packet between their TUN devices, dropping a seeded share and
delaying the rest, so TCP sees real loss (no kernel module, no netem). Where
namespaces cannot be made, a TCP proxy on loopback cuts and delays instead,
and the rows with loss say n/a. A freeze is SIGSTOP then SIGCONT; a kill is
SIGKILL, and the helper is started again 2 s later.

Columns, from the coordinator's trace: *detection* is the fault to its
first `failure`, `robot-lost` or `stale` event, *switch* to its first
`switch` or `no-configuration` (medians; `(k/n)` when only k of n trials saw
one; `-` none), *recovery* the condition clearing (the SIGCONT, the link
restored, the restarted process's `start` event) to the goal's action
running on fresh data again. A *permanent stop* is a trial where that did
not happen within 20 s. *Spurious switches* are switches and stops under
≤ 10 % loss or the delay (other rows: `-`). *Served during fault* is the
share of the cycles of the fault in which the goal's action ran (median).
A row is ✓ when every trial recovered within hold + 1 s, and the light rows
had no switch.
"""


def _seconds(values: list[float | None], trials: int) -> str:
    seen = [v for v in values if v is not None]
    if not seen:
        return "-"
    text = f"{statistics.median(seen):.2f}"
    return text if len(seen) == len(values) == trials else f"{text} ({len(seen)}/{trials})"


def row(condition: Condition, trials: list[Trial], options: Options) -> list[str]:
    """The table's row for the trials of ``condition``."""
    if not trials:
        return [condition.name, "0", "n/a (no netns)", *["-"] * (len(HEADER) - 4), "n/a"]
    n = len(trials)
    done = [t for t in trials if not t.error]
    recovered = [t.recovery for t in done if t.recovery is not None]
    stops = sum(1 for t in done if t.recovery is None)
    recovery = "-"
    if recovered:
        low, mid, high = min(recovered), statistics.median(recovered), max(recovered)
        recovery = f"{low:.2f} / {mid:.2f} / {high:.2f}"
    served = [t.served for t in done if t.served is not None]
    limit = options.hold + 1.0
    ok = (
        len(done) == n
        and stops == 0
        and all(r <= limit for r in recovered)
        and all(t.spurious == 0 for t in done)
    )
    errors = n - len(done)
    return [
        condition.name,
        str(n) + (f" ({errors} not run)" if errors else ""),
        _seconds([t.detection for t in done], len(done)),
        _seconds([t.switch for t in done], len(done)),
        recovery,
        str(sum(t.spurious for t in done)) if condition.light else "-",
        f"{stops}/{len(done)}",
        f"{statistics.median(served):.0%}" if served else "-",
        "✓" if ok else "✗",
    ]


EVIDENCE_LINES = 6
"""Of the coordinator's events of a trial over the limit: the first ones, and
as many before the fault cleared (then every one after it)."""


def evidence_of(trial: Trial, most: int = EVIDENCE_LINES) -> str:
    """The coordinator's events of a trial: the first ``most`` from the fault
    on, the last ``most`` before it cleared, the clearing, and all after."""
    before = [e for e in trial.events if e[0] < trial.cleared]
    shown = [f"    +{t:.2f}s {what}" for t, what in before]
    if len(before) > 2 * most:
        shown[most:-most] = [f"    ... {len(before) - 2 * most} more"]
    shown.append(f"    +{trial.cleared:.2f}s -- the fault cleared --")
    shown += [f"    +{t:.2f}s {what}" for t, what in trial.events[len(before) :]]
    return "\n".join(shown)


def make_link(choice: str, seed: int) -> Link:
    """The lossy link: namespaces when possible (``auto``), or as chosen."""
    if choice in ("auto", "netns"):
        try:
            return NetnsLink(seed=seed)
        except LinkUnavailable as error:
            if choice == "netns":
                raise
            print(f"note: no netns link ({error}); a TCP proxy instead", file=sys.stderr)
    return ProxyLink(target=free_port())


def run(
    conditions: list[Condition], options: Options, link: Link, keep: Path | None, verbose: bool
) -> tuple[list[list[str]], list[str]]:
    """Every trial; the rows, and the evidence of the trials that missed the limit."""
    rows, evidence = [], []
    with tempfile.TemporaryDirectory(prefix="cfgplan-faults-") as scratch:
        base = keep or Path(scratch)
        for c_index, condition in enumerate(conditions):
            if condition.kind == "loss" and not link.can_lose:
                rows.append(row(condition, [], options))
                continue
            trials = []
            for index in range(options.trials):
                folder = base / f"c{c_index}-t{index}"
                folder.mkdir(parents=True, exist_ok=True)
                try:
                    trial = run_trial(condition, options, link, folder)
                except TrialError as error:
                    trial = Trial(error=str(error))
                trials.append(trial)
                late = trial.recovery is None or trial.recovery > options.hold + 1.0
                if trial.error or late or trial.spurious:
                    shown = trial.error or evidence_of(trial)
                    evidence.append(f"- {condition.name}, trial {index + 1}:\n{shown}")
                if verbose:
                    figures = (trial.detection, trial.switch, trial.recovery, trial.served)
                    shown = " ".join("-" if f is None else f"{f:.2f}" for f in figures)
                    what = trial.error or f"detection switch recovery served: {shown}"
                    print(f"{condition.name} #{index + 1}: {what}", file=sys.stderr, flush=True)
            rows.append(row(condition, trials, options))
    return rows, evidence


PAGE = """\
<!-- Written by `python -m benchmarks.faults --markdown ...`: do not edit by hand. -->

# Faults

{intro}
## The last run

{facts}

{table}

{evidence}{beyond}
Made with `{shown}`; run it again to regenerate this page.
"""

BEYOND = """\
## Beyond one helper and one link

The rows above are two robots, peers on one link. Two more benchmarks go
further, each with a page of its own; their last runs' tables are below as
those pages have them, each with the facts of its run (machine, date,
revision, load, trials).

### Loss on one link, a healthy robot beside it

The [link-loss page](link-loss.md) (`python -m benchmarks.link_loss`) puts a third robot
beside the coordinator on a healthy link and drops half of the packets on
the helper's link for 30 s, with the code before and after side by side.
Zenoh sends declarations with congestion control *block*, and a send to a
client whose queue the loss has filled waits, up to `wait_before_close`
(5 s by default), on the thread that sends: in a router, the one reading
the healthy link the declaration came on, whose keep-alives then go unread
past the lease; the router drops that healthy robot. cfgplan now closes a
stuck link after a twentieth of the lease (100 ms), for the router and
every robot (a slow test in two network namespaces: the healthy client's
longest gap 0.13 s, against 5.6 s and its loss). A second stall of the
router comes from Zenoh's 10 s `SO_LINGER` on TCP links: a failed
handshake with the lossy robot is dropped on the one thread that drives
the I/O of every link the router accepted, and `close(2)` waits there for
a FIN the loss eats, up to 10 s, while no client is read. cfgplan gives
Zenoh spare threads, which cut that stall to the lease (1.8 s against 10 s
in a slow test) but not to nothing: the fix is Zenoh's. The
coordinator, knowing its own link to the router is gone, now holds the
losses it sees while the cut lasts and two leases more, and records no
failure of a robot that comes back (a slow test freezes the router 3 s);
its goal cannot be served while the router routes nothing.

{link_loss}

### The society at scale, with and without its keys

The [scale page](scale.md) (`python -m benchmarks.scale`) launches
societies of 2 to 50 robots, through launch's router, with the society's
keys through its secured router, and in a mesh, and kills the helper in
use: the connections, idle traffic, memory, start-up and switch at each
size. What the society does when its router freezes or dies, with keys and
without, is tested (`tests/security/test_secured_router.py`,
`tests/cli/test_launch.py`), not measured here.

{scale}
"""

LINK_LOSS_PAGE = Path(__file__).resolve().parents[1] / "docs" / "explanation" / "link-loss.md"
SCALE_PAGE = Path(__file__).resolve().parents[1] / "docs" / "explanation" / "scale.md"


def last_run(path: Path, tables: int) -> str:
    """The facts of the last run a benchmark's page shows and its first
    ``tables`` tables, as the page has them (its figures are that run's)."""
    if not path.exists():
        return f"({path.name} has no run yet)"
    text = path.read_text(encoding="utf-8")
    if "## The last run\n" not in text:
        raise SystemExit(f"{path}: not a page a benchmark wrote")
    blocks = [b.strip("\n") for b in text.split("## The last run\n", 1)[1].split("\n\n")]
    facts = next(b for b in blocks if b.startswith("- machine:"))
    found = [b.strip() for b in blocks if b.startswith("|")][:tables]
    made = re.search(r"^Made with `(.*?)`", text, re.M)
    said = f"From [{path.name}]({path.name}), made with `{made[1]}`:" if made else ""
    return "\n\n".join([said, facts, *found]).strip()


def beyond() -> str:
    """The section on the other fault benchmarks, with their pages' last runs."""
    return BEYOND.format(link_loss=last_run(LINK_LOSS_PAGE, 1), scale=last_run(SCALE_PAGE, 2))


def page(
    options: Options, lines: list[str], facts: list[str], evidence: list[str], command: list[str]
) -> str:
    """The documentation page of this run with ``options``; ``evidence``: the
    coordinator's events in the trials over the limit."""
    shown = shlex.join(["python", "-m", "benchmarks.faults", *command])
    heading = "### Trials over the limit: the coordinator's events from the fault on"
    over = "\n".join([heading, "", "```text", *evidence, "```", "", ""]) if evidence else ""
    return PAGE.format(
        intro=INTRO.format(lease=options.lease, hold=options.hold),
        facts="\n".join(facts),
        table="\n".join(lines),
        evidence=over,
        beyond=beyond(),
        shown=shown,
    )


def rewrite(path: Path) -> None:
    """Write the page at ``path`` again in this module's words: its own run
    (facts, table, the trials over the limit) kept as it is, the other
    benchmarks' last runs taken again from their pages (nothing is measured)."""
    text = path.read_text(encoding="utf-8")
    made = re.search(r"^Made with `python -m benchmarks\.faults ?(.*?)`; run it again", text, re.M)
    if made is None or "## The last run\n" not in text:
        raise SystemExit(f"{path}: not a page benchmarks.faults wrote")
    run = text.split("## The last run\n", 1)[1].split("## Beyond one helper and one link", 1)[0]
    blocks = [b.strip("\n") for b in run.split("\n\n") if b.strip()]
    facts = next(b for b in blocks if b.startswith("- machine:")).splitlines()
    lines = next(b for b in blocks if b.startswith("|")).splitlines()
    over = run.split("```text\n", 1)[1].split("\n```", 1)[0] if "```text\n" in run else ""
    command = shlex.split(made[1])
    options = options_of(parser().parse_args(command))
    path.write_text(page(options, lines, facts, [over] if over else [], command), encoding="utf-8")


def parser() -> argparse.ArgumentParser:
    """The command line of ``python -m benchmarks.faults``."""
    out = argparse.ArgumentParser(
        prog="python -m benchmarks.faults", description=__doc__.splitlines()[0] if __doc__ else ""
    )
    out.add_argument("--trials", type=int, default=3, help="trials per condition (3)")
    out.add_argument(
        "--loss-seconds", type=float, help="a loss or delay row lasts (30; --quick: 5)"
    )
    out.add_argument("--quick", action="store_true", help="1 trial, loss rows of 5 s")
    out.add_argument("--only", action="append", default=[], help="conditions whose name has this")
    out.add_argument("--link", choices=["auto", "netns", "proxy"], default="auto")
    out.add_argument("--seed", type=int, default=33, help="the link's dropped packets (33)")
    out.add_argument("--markdown", type=Path, help="also write the documentation page here")
    out.add_argument("--keep", type=Path, help="keep every trial's traces and logs here")
    out.add_argument("--verbose", action="store_true", help="each trial's figures on stderr")
    out.add_argument(
        "--rewrite",
        type=Path,
        metavar="PAGE",
        help="write PAGE again in this module's words: its run kept, the link-loss and scale "
        "pages' last runs taken again (nothing is measured)",
    )
    return out


def options_of(args: argparse.Namespace) -> Options:
    """The options of a command line (:class:`ValueError` when they make no run)."""
    seconds = args.loss_seconds
    if seconds is None:
        seconds = 5.0 if args.quick else 30.0
    if args.trials < 1 or seconds <= 0:
        raise ValueError("--trials must be 1 or more and --loss-seconds above 0")
    return Options(trials=1 if args.quick else args.trials, loss_seconds=seconds, seed=args.seed)


def main(argv: list[str] | None = None) -> int:
    command = parser()
    args = command.parse_args(argv)
    if args.rewrite:
        rewrite(args.rewrite)
        print(f"wrote {args.rewrite}")
        return 0
    try:
        options = options_of(args)
    except ValueError as error:
        command.error(str(error))
    conditions = [c for c in CONDITIONS if not args.only or any(o in c.name for o in args.only)]
    if not conditions:
        print(f"error: no condition matches {args.only}", file=sys.stderr)
        return 1
    try:
        link = make_link(args.link, options.seed)
    except LinkUnavailable as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    load_before = os.getloadavg()
    started = time.monotonic()
    try:
        rows, evidence = run(conditions, options, link, args.keep, args.verbose)
    finally:
        link.close()
    load_after = os.getloadavg()
    facts = [
        f"- machine: {machine()}",
        f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
        f"- revision: `{revision()}`",
        f"- link: {link.kind}; loss seed {options.seed}; loss rows last {options.loss_seconds:g} s",
        f"- load average (1 min) before / after: {load_before[0]:.2f} / {load_after[0]:.2f}; "
        f"{time.monotonic() - started:.0f} s in all",
        f"- limit: recovery within hold + 1 s = {options.hold + 1.0:g} s of the fault clearing",
    ]
    lines = table(HEADER, rows).splitlines()
    print("\n".join([*facts, "", *lines]))
    if evidence:
        print("\nTrials over the limit (the coordinator's events from the fault on):")
        print("\n".join(evidence))
    if args.markdown:
        args.markdown.write_text(
            page(options, lines, facts, evidence, sys.argv[1:] if argv is None else argv)
        )
        print(f"\nwrote {args.markdown}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
