"""The threat model, measured: ``python -m benchmarks.threats`` runs the attack tests.

Each :class:`Threat` names an attack on a society — by a stranger on its
network, by a member holding a valid key, by a local process, through the
messages themselves — what refuses it now, and the tests that make that
attack: on real processes and sessions over Zenoh (loopback, TLS with the
society's keys where the attack needs them), or on the component that
refuses it. A threat with nothing that refuses it says so, and what limits
it.

The script runs every test the threats name once, in one ``pytest`` run
(the slow ones too: ``-m ""``), reads each one's outcome, time and what it
recorded (pytest's ``record_property``: a flood's rate, the coordinator's
cycles under it, ...), and prints the table; ``--markdown FILE`` writes the
documentation's page (``docs/explanation/threat-model.md``), with the
machine, its load before and after, the revision and the time the run took.
Nothing is measured but by the tests; a test that fails is shown failing.
"""

from __future__ import annotations

import argparse
import os
import shlex
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.page import revision
from benchmarks.reconfigure import ROOT, table
from benchmarks.run import machine

SCALE_PAGE = ROOT / "docs" / "explanation" / "scale.md"
KEYED = "router + keys"
"""The scale page's rows with the society's keys (:data:`benchmarks.scale.KEYED`)."""

ATTACKS = "tests/security/test_attacks.py"
MEMBERS = "tests/security/test_member_attacks.py"
ROUTED = "tests/security/test_secured_router.py"
SWITCH = "tests/reconfigure/test_network_switch.py"
SUCCESSION = "tests/reconfigure/test_succession.py"


@dataclass(frozen=True)
class Threat:
    """An attack, what refuses it (empty: nothing does; ``limits`` says what
    bounds it), and the tests that make it (``file::function``)."""

    attack: str
    refused: str
    tests: tuple[str, ...] = ()
    keys: bool = False
    """Refused only in a society run with its keys (``--keys``)."""
    limits: str = ""


THREATS: tuple[Threat, ...] = (
    Threat(
        "A stranger on the network reads every channel value, liveliness token and switch, "
        "or sends them",
        "a peer without a certificate of the society's authority cannot open a session: "
        "TLS with mutual authentication, with a robot as with the society's secured router "
        "(plain TCP, TLS without a certificate and a certificate of another authority, under "
        "the society's name and its robots' names, are all refused)",
        (
            f"{ATTACKS}::test_a_keyed_society_serves_its_goal_and_strangers_read_nothing",
            f"{ROUTED}::test_the_secured_router_refuses_strangers_and_holds_members_to_their_rights",
        ),
        keys=True,
    ),
    Threat(
        "A society run without keys: anyone who reaches its network reads and steers it",
        "",
        (
            "tests/security/test_zenoh_tls.py::"
            "test_a_society_without_keys_is_said_to_be_open_and_one_with_keys_is_not",
        ),
        limits="every robot says so when it starts (cfgplan keys new, then --keys DIR)",
    ),
    Threat(
        "Two societies under one name on one network (a second team's, or a robot restarted "
        "with an edited state)",
        "every robot announces the fingerprint of its problem; one that met no robot of its "
        "own problem stops alone, naming both problems and --society NAME, and the society "
        "goes on; with keys, a robot of another authority cannot connect at all",
        (
            "tests/runtime/test_society_name.py::test_a_robot_of_another_problem_is_refused_alone",
            "tests/reconfigure/test_network_restart.py::"
            "test_a_helper_restarted_with_an_edited_state_is_refused_alone",
        ),
    ),
    Threat(
        "With a robot's key, a value on a channel in another robot's name",
        "a channel's key names its sender and a member may put only on keys naming itself: "
        "each robot holds its peers to it, the secured router each client; a receiver "
        "listens only to the sender it expects",
        (
            f"{ATTACKS}::test_a_robot_cannot_forge_a_value_on_another_robots_channel",
            f"{ROUTED}::test_the_secured_router_refuses_strangers_and_holds_members_to_their_rights",
        ),
        keys=True,
    ),
    Threat(
        "With a robot's key, a report to the coordinator in another robot's name (a robot "
        "lost, a task accomplished, a fact removed)",
        "each robot reports on its own key to the coordinator and only it may put there; a "
        "report whose robot is not its key's is dropped and said",
        (
            f"{ATTACKS}::test_a_robot_cannot_forge_a_value_on_another_robots_channel",
            f"{SWITCH}::test_a_report_of_another_robots_detection_is_dropped_and_said",
        ),
        keys=True,
    ),
    Threat(
        "With the key of a robot that is no coordinator, the steps of a switch (prepare, "
        "commit, finish) sent to a robot",
        "only a coordinator's certificate may put on a robot's configure key: each robot "
        "holds its peers to it, the secured router each client",
        (
            f"{ATTACKS}::test_members_beyond_their_rights_get_nothing_through",
            f"{ROUTED}::test_the_secured_router_refuses_strangers_and_holds_members_to_their_rights",
        ),
        keys=True,
    ),
    Threat(
        "With a robot's key, another robot's liveliness token (to fake it alive)",
        "a robot may declare only its own tokens: each robot holds its peers to it, the "
        "secured router each client",
        (
            f"{ATTACKS}::test_members_beyond_their_rights_get_nothing_through",
            f"{ROUTED}::test_the_secured_router_refuses_strangers_and_holds_members_to_their_rights",
        ),
        keys=True,
    ),
    Threat(
        "With a robot's key, or an operator tool's, reading the others' channels and reports, "
        "or sending anything as a tool",
        "a robot subscribes to its own keys only and is sent only those; an operator tool "
        "reads and sends nothing",
        (f"{ATTACKS}::test_members_beyond_their_rights_get_nothing_through",),
        keys=True,
    ),
    Threat(
        "With a robot's key, on its own channel, a value whose envelope says it is from "
        "another robot",
        "the key names the sender: the value is refused and said",
        (
            f"{ATTACKS}::test_a_member_says_nothing_of_what_is_not_its_own",
            f"{SWITCH}::test_a_message_that_says_it_is_from_another_robot_than_its_key_is_dropped",
        ),
    ),
    Threat(
        "With a robot's key, in its own name, a report of another robot's failure, recovery "
        "or accomplished task, or a state update (remove (camera Emil): the society stopped)",
        "a report speaks only of the instances that run on its robot and of its own inputs; "
        "a state update is the coordinator's operator's alone; any other is dropped and said",
        (
            f"{ATTACKS}::test_a_member_says_nothing_of_what_is_not_its_own",
            f"{SWITCH}::test_a_helper_speaks_only_of_what_is_its_own",
        ),
    ),
    Threat(
        "With a robot's key, a forged rival of the coordinator's own epoch (read from the "
        "duplicate answered to a forged ready), naming any leader: the coordinator stopped",
        "a rival from a robot that follows this coordinator is believed only when the "
        "coordinator's own view bears it out (the leader named is another process of its "
        "own robot, or a live robot marked a coordinator); else it goes on and says so — "
        "among peers and through the secured router",
        (
            f"{MEMBERS}::test_a_forged_rival_does_not_stop_the_coordinator",
            f"{SWITCH}::test_a_rival_that_the_coordinators_own_view_does_not_bear_out_is_not_believed",
        ),
    ),
    Threat(
        "With a robot's key, a problem token of another problem under its own name (without "
        "keys, under any name): every robot stopped",
        "only a robot that met no robot of its own problem stops on another's token; the "
        "robots of a running society say once that the token is not theirs and go on",
        (
            f"{MEMBERS}::test_a_problem_token_of_another_problem_stops_nobody",
            "tests/runtime/test_society_name.py::"
            "test_two_transports_of_different_problems_refuse_one_of_the_same_joins",
        ),
        limits="a token declared before a society's first robots meet makes a robot that "
        "meets only it stop (it met no robot of its own problem yet)",
    ),
    Threat(
        "With a robot's key, a flood of its key to the coordinator (thousands of messages a "
        "second, unreadable or not its own to say): the coordinator's loop stalled and its "
        "trace grew by an event per message",
        "a token bucket per key of the protocol (each key is one sender's): what is over it "
        "is dropped unread; what passes and is refused is said once per kind, sender and "
        "second with a count; the loop keeps its rate — among peers and through the "
        "secured router",
        (
            f"{MEMBERS}::test_a_flood_of_the_coordinators_control_key_neither_stalls_nor_fills_the_trace",
            "tests/runtime/test_rate_limit.py::"
            "test_a_protocol_key_takes_its_burst_then_its_rate_whatever_is_said",
        ),
    ),
    Threat(
        "With a robot's key, a flood of one of its channels",
        "a token bucket per channel and sender (--rate-allowance messages per period of "
        "the sender, 200 a second at most after a burst): the rest are dropped before they "
        "are read, and said once a second",
        (
            "tests/runtime/test_rate_limit.py::"
            "test_a_flood_on_a_channel_is_cut_to_its_allowance_and_recorded",
        ),
    ),
    Threat(
        "With a robot's key, its liveliness token held up by another session, then the robot "
        "killed: its death showed only as stale inputs",
        "the robot's process token going is its loss when its name stays alive for more "
        "than half a second after it; said once",
        (
            f"{MEMBERS}::test_a_name_held_alive_by_a_session_does_not_hide_its_robots_death",
            f"{SWITCH}::test_a_process_that_ended_while_its_name_stays_alive_is_lost",
        ),
    ),
    Threat(
        "A second process of a live robot, or a frozen one back beside its replacement",
        "each process declares a token of its own; the second is told it is a duplicate and stops",
        (
            f"{SWITCH}::test_a_second_process_of_a_live_robot_is_told_to_stop",
            f"{SWITCH}::test_a_second_process_is_told_apart_by_its_process_token",
            "tests/reconfigure/test_network_restart.py::"
            "test_a_frozen_helper_back_next_to_its_replacement_is_told_it_is_a_duplicate",
        ),
    ),
    Threat(
        "With a robot's key, a raw session that declares no process token",
        "",
        limits="it is not taken for a second process of the robot; it may say only what "
        "that robot may say (the rows above), and cannot hide the robot's death (its "
        "process token)",
    ),
    Threat(
        "A second coordinator of the society's goal",
        "a robot follows one coordinator's run (its epoch) and answers any other one "
        "rival; a coordinator told it is a rival stops",
        (
            "tests/runtime/test_member.py::"
            "test_a_second_coordinator_is_told_it_is_a_rival_and_not_followed",
            f"{SWITCH}::test_a_coordinator_told_it_is_a_rival_stops",
        ),
    ),
    Threat(
        "With a coordinator's key, a run of a later generation sent to the robots, to take "
        "the society over",
        "a robot follows a later run only once the coordinator it follows is gone, and only "
        "from the robot next in the order of succession it derives from the goals; any "
        "other is refused (rival) and said",
        (
            f"{SUCCESSION}::test_a_robot_fences_off_older_runs_and_follows_a_later_one_only_from_the_next",
        ),
    ),
    Threat(
        "With a robot's key, a rival saying it follows a later run of another live "
        "coordinator robot, to make the coordinator step down",
        "a coordinator steps down only on the successor's own word, and only for the robot "
        "next after it in the order, alive",
        (
            f"{SUCCESSION}::test_a_coordinator_steps_down_only_for_the_robot_next_in_the_order_alive",
        ),
    ),
    Threat(
        "With a member's key, false things in its own name: values on the channels it sends, "
        "reports about its own functionalities; with a coordinator's, switches",
        "",
        limits="at its allowance of messages; keep the society's certificates to robots you "
        "trust, and a compromised robot's key out of it (renew)",
    ),
    Threat(
        "A period of 1e9 s in one channel message, to switch staleness off",
        "a period over 60 s, or a time that is not a finite number, is refused",
        ("tests/runtime/test_values.py::test_the_envelope_round_trip_and_what_is_refused",),
    ),
    Threat(
        "A number JSON has not (NaN, Infinity), or one too big for a message's id",
        "not JSON, or not a whole number: refused and said, never raised in the loop; a "
        "robot never sends one (its output is refused at the door) and writes one to a "
        "trace as a string",
        (
            "tests/runtime/test_values.py::test_a_message_with_a_nan_is_not_json_and_not_taken",
            "tests/runtime/test_member.py::"
            "test_a_message_whose_id_is_no_whole_number_is_an_error_not_a_crash",
        ),
    ),
    Threat(
        "Code of the attacker's choice run by a robot",
        "messages are JSON, read field by field; malformed answers and reports are ignored "
        "even during a switch; a part calls only registered implementations",
        (f"{SWITCH}::test_malformed_answers_and_reports_are_ignored_even_during_a_switch",),
    ),
    Threat(
        "Any few local processes hold every stream of the live page (--live) and never read: "
        "the operator's page was refused",
        "a new stream takes the place of the one whose client reads least, else of the oldest",
        (
            "tests/live/test_server.py::test_clients_holding_every_stream_cannot_lock_the_operator_out",
        ),
    ),
    Threat(
        "A local user reads a trace: every value of the run",
        "a trace (and a recording) is its owner's only, mode 0600, every line JSON",
        ("tests/runtime/test_trace.py::test_a_trace_is_its_owners_only_and_every_line_json",),
    ),
    Threat(
        "A robot that only connects also listens on every interface (Zenoh's default)",
        "a robot listens only where told (--listen or a configuration file)",
        ("tests/runtime/test_zenoh_config.py::test_a_robot_that_only_connects_listens_nowhere",),
    ),
    Threat(
        "A robot's key leaked",
        "cfgplan keys renew NAME: a new key of the next generation; every member given the "
        "new society.json admits the old certificate for nothing",
        (
            "tests/security/test_renew.py::test_the_old_certificate_can_no_longer_publish_the_new_one_can",
        ),
        keys=True,
    ),
    Threat(
        "The router's key leaked, or its host taken",
        "",
        (
            "tests/security/test_zenoh_tls.py::"
            "test_the_router_holds_each_client_to_its_rules_and_each_holds_the_router_to_them",
        ),
        keys=True,
        limits="it can put, in any member's name, on every key a robot reads (the router "
        "vouches for who sent what); each robot still takes from it only what that robot "
        "may be sent (its access control, the router's rules mirrored) and checks every "
        "message as from any member (the rows above); cfgplan keys renew router replaces "
        "its key",
    ),
    Threat(
        "The authority's key (ca.key) leaked",
        "",
        keys=True,
        limits="make the society's keys again (cfgplan keys new --force) and give every host "
        "its new files: the old authority's certificates are then of no use",
    ),
    Threat(
        "Anyone who reaches a router's port, or a listening robot's: TCP connections opened "
        "and then cut, their close never acknowledged, each hold one of Zenoh's threads that "
        "accept links for 10 s (the SO_LINGER Zenoh sets on every TCP link); while all of "
        "them wait, no link of that process is read and healthy robots are lost",
        "",
        (
            "tests/runtime/test_stuck_handshake.py::"
            "test_a_failed_handshake_on_a_dead_link_stalls_healthy_clients_no_longer_than_the_lease",
        ),
        limits="cfgplan starts Zenoh with 8 such threads (ZENOH_RUNTIME, unless set), so one "
        "handshake failed on a dead link stalls the healthy clients about a lease, not 10 s, "
        "and a robot is lost once at most; 8 at once still stall it (keys do not help: the "
        "close comes before TLS); the fix is Zenoh's (no linger on its sockets)",
    ),
)


@dataclass
class Outcome:
    """What a test did in the run: each of its cases (parameters) passed or not."""

    cases: list[tuple[str, bool]] = field(default_factory=list)  # (case id, passed)
    seconds: float = 0.0
    figures: list[tuple[str, str, str]] = field(default_factory=list)  # (case, name, value)

    @property
    def passed(self) -> bool:
        return bool(self.cases) and all(ok for _, ok in self.cases)


def node_ids() -> list[str]:
    """Every test the threats name, once, in their order."""
    return list(dict.fromkeys(t for threat in THREATS for t in threat.tests))


def outcomes(report: Path) -> dict[str, Outcome]:
    """Each named test's outcome, from a JUnit XML report of pytest."""
    found = {node: Outcome() for node in node_ids()}
    by_case = {(n.split("::")[0][:-3].replace("/", "."), n.split("::")[1]): n for n in found}
    for case in ElementTree.parse(report).getroot().iter("testcase"):
        name = case.get("name", "")
        base, _, param = name.partition("[")
        node = by_case.get((case.get("classname", ""), base))
        if node is None:
            continue
        failed = any(case.find(tag) is not None for tag in ("failure", "error", "skipped"))
        outcome = found[node]
        outcome.cases.append((param.rstrip("]"), not failed))
        outcome.seconds += float(case.get("time", "0"))
        for prop in case.iter("property"):
            outcome.figures.append((param.rstrip("]"), prop.get("name", ""), prop.get("value", "")))
    return found


def run_tests(report: Path) -> int:
    """Run every named test once; pytest's exit status."""
    command = [sys.executable, "-m", "pytest", "-m", "", "-q", "-p", "no:cacheprovider"]
    command += ["-o", "junit_family=xunit1", f"--junitxml={report}", *node_ids()]
    return subprocess.run(command, cwd=ROOT).returncode


def labels() -> dict[str, str]:
    """A short label per named test: T1, T2, ... in their order."""
    return {node: f"T{i}" for i, node in enumerate(node_ids(), 1)}


def verdict(threat: Threat, found: dict[str, Outcome]) -> str:
    """The threat's cell of tests: each one's label with ✓ or ✗."""
    if not threat.tests:
        return "-"
    names = labels()
    return ", ".join(f"{names[t]} {'✓' if found[t].passed else '✗'}" for t in threat.tests)


def threat_rows(found: dict[str, Outcome]) -> list[list[str]]:
    rows = []
    for threat in THREATS:
        refused = threat.refused or f"**not refused**: {threat.limits}"
        if threat.refused and threat.limits:
            refused += f"; {threat.limits}"
        if threat.keys:
            refused = f"*keys*: {refused}"
        rows.append([threat.attack, refused, verdict(threat, found)])
    return rows


def listed_tests(found: dict[str, Outcome]) -> list[str]:
    """One line per test: its label, where it is, how it went, what it recorded."""
    out = []
    for node, label in labels().items():
        outcome = found[node]
        cases = outcome.cases
        if not cases:
            said = "not run"
        else:
            passed = sum(1 for _, ok in cases if ok)
            params = [c for c, _ in cases if c]
            which = f" ({', '.join(params)})" if params else ""
            said = f"passed {passed} of {len(cases)}{which} in {outcome.seconds:.0f} s"
        line = f"- {label} `{node}`: {said}"
        figures = [f"{c + ': ' if c else ''}{name} {value}" for c, name, value in outcome.figures]
        if figures:
            line += "; it recorded " + "; ".join(figures)
        out.append(line)
    return out


def keyed_rows(page: Path = SCALE_PAGE) -> str:
    """The scale page's start and kill tables cut to the sizes measured with the
    society's keys, with and without them (its run's facts are on that page)."""
    if not page.exists():
        return "(the scale page has no run yet)"
    text = page.read_text(encoding="utf-8").split("## The last run\n", 1)[-1]
    blocks = [b.strip() for b in text.split("\n\n")]
    tables = [b for b in blocks if b.startswith("|")][:2]
    cut = []
    for block in tables:
        lines = block.splitlines()
        keyed = {line.split("|")[1].strip() for line in lines[2:] if f"| {KEYED} |" in line}
        keep = [line for line in lines[2:] if line.split("|")[1].strip() in keyed]
        keep = [line for line in keep if "| mesh |" not in line]
        cut.append("\n".join([*lines[:2], *keep]))
    facts = next((b for b in blocks if b.startswith("- machine:")), "")
    return "\n\n".join([facts, *cut])


INTRO = """\
Who can reach a society's network — a stranger's laptop on the same LAN, a
second society under the same name, a robot of the society that was
compromised, a local user of a robot's host — and what refuses each attack
now. `python -m benchmarks.threats` runs the tests that make each attack,
once, and writes this page from that run: a row is refused when its tests
passed in the run below (✓), on real processes and Zenoh sessions
(loopback, the society's keys where the row says *keys*) or on the component
that refuses it. The figures are what the tests recorded as they attacked.
A society started without keys says, when it starts, that anyone on the
network can read and steer it; with keys (see [Secure a
society](../how-to/secure-a-society.md)) its links are TLS with mutual
authentication, and the society's access control is enforced by every robot
on its peers and, behind the society's secured router, by the router on
every robot and by every robot on the router.
"""

PAGE = """\
<!-- Written by `{shown}`: do not edit by hand. -->

# Threat model

{intro}
## The last run

{facts}

{table}

The tests (each file's own docstring says how it attacks):

{tests}

## The society at scale with its keys

The [scale page](scale.md) measures what the keys cost: the sizes run with
the society's keys, through its secured router, beside the same sizes
without them, as that page's last run has them:

{scale}

Made with `{shown}`; run it again to regenerate this page. The faults a
society rides out are on the [faults page](faults.md).
"""

HEADER = ["attack", "what refuses it now", "tests"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.threats", description=__doc__.splitlines()[0] if __doc__ else ""
    )
    parser.add_argument("--markdown", type=Path, help="also write the documentation page here")
    args = parser.parse_args(argv)
    load_before, started = os.getloadavg(), time.monotonic()
    with tempfile.TemporaryDirectory(prefix="cfgplan-threats-") as folder:
        report = Path(folder) / "report.xml"
        status = run_tests(report)
        found = outcomes(report)
    load_after = os.getloadavg()
    cases = [ok for outcome in found.values() for _, ok in outcome.cases]
    facts = [
        f"- machine: {machine()}",
        f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}",
        f"- revision: `{revision()}`",
        f"- tests: {len(found)} ({len(cases)} with their parameters), {sum(cases)} passed; "
        f"pytest's exit status {status}",
        f"- load average (1 min) before / after: {load_before[0]:.2f} / {load_after[0]:.2f}; "
        f"{time.monotonic() - started:.0f} s in all",
    ]
    shown_table = table(HEADER, threat_rows(found))
    tests = "\n".join(listed_tests(found))
    print("\n\n".join(["\n".join(facts), shown_table, tests]))
    if args.markdown:
        shown = shlex.join(["python", "-m", "benchmarks.threats", *(argv or sys.argv[1:])])
        text = PAGE.format(
            shown=shown,
            intro=INTRO,
            facts="\n".join(facts),
            table=shown_table,
            tests=tests,
            scale=keyed_rows(),
        )
        args.markdown.write_text(text, encoding="utf-8")
        print(f"\nwrote {args.markdown}")
    return 0 if status == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
