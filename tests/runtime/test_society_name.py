"""Two problems under one society name detect each other and refuse, naming both
(a secured society's rule); robots of one problem still join. The fingerprint's rules
(:mod:`cfgplan.security.identity`) are tested without a network; the
processes are hermetic (loopback, free ports, scouting off, bounded waits,
stopped by pid)."""

from __future__ import annotations

import contextlib
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cfgplan.problem import load
from cfgplan.runtime.keys import problem_key, problem_of_token, problem_pattern
from cfgplan.security.identity import MAX_ABOUT, ProblemId, problem_id
from cfgplan.security.keys import make_society, plan_society, write_society
from tests.backends.support import DOMAINS, EXAMPLE_IMPL
from tests.runtime.netutil import (
    Processes,
    endpoint,
    first,
    free_port,
    hermetic_config,
    processes,
    read_trace,
    wait_for,
)

DOMAIN = DOMAINS / "cross-door/domain.lisp"
STEP1 = DOMAINS / "cross-door/state-6.2.2-step1.lisp"
STEP2 = DOMAINS / "cross-door/state-6.2.2-step2.lisp"
LIMIT = 60.0


def _id(domain: Path, state: Path, goals: list[str] | None = None) -> ProblemId:
    return problem_id(load(domain, state, goals or [], None), domain, state)


def test_the_fingerprint_ignores_layout_and_comments_not_meaning(tmp_path: Path) -> None:
    """The same domain and state, reformatted and commented, give the same
    fingerprint; another state, another goal or a changed fact give another.
    The description names the files and the goal."""
    same_domain = tmp_path / "d.lisp"
    text = DOMAIN.read_text()
    same_domain.write_text("; a comment\n\n" + text.replace("\n", "\n\n"))
    base = _id(DOMAIN, STEP2)
    assert _id(same_domain, STEP2).fingerprint == base.fingerprint
    assert _id(DOMAIN, STEP1).fingerprint != base.fingerprint
    changed = tmp_path / "s.lisp"
    changed.write_text(STEP2.read_text().replace("Door1", "Door2"))
    assert _id(DOMAIN, changed).fingerprint != base.fingerprint
    other_goal = _id(DOMAIN, STEP2, ["(do-cross-door Pippi Door1)"])
    assert other_goal.fingerprint != base.fingerprint
    assert base.about == "domain.lisp with state-6.2.2-step2.lisp, goal do-cross-door(Emil, Door1)"


def test_a_problem_token_is_read_bounded() -> None:
    """A token round-trips through its key; one of another society, of another
    shape, too long or not a fingerprint is not taken; a description is clipped
    and escaped."""
    key = problem_key("lab", "Pippi", "0123456789abcdef", "d.lisp with s.lisp, goal g(a/b)")
    assert problem_of_token(key, "lab") == (
        "Pippi",
        "0123456789abcdef",
        "d.lisp with s.lisp, goal g(a/b)",
    )
    assert problem_of_token(key, "other") is None
    assert problem_of_token(key + "/more", "lab") is None
    assert problem_of_token("cfgplan/lab/Pippi/problem/x/" + "y" * 5000, "lab") is None
    assert problem_pattern("lab") == "cfgplan/lab/*/problem/*/*"
    with pytest.raises(ValueError):
        ProblemId("not hex", "x")
    long = ProblemId("0123456789abcdef", "\x1b[31m" + "z" * 1000)
    assert len(long.about) == MAX_ABOUT and "\x1b" not in long.about


def _robot(
    running: Processes, folder: Path, state: Path, name: str, tag: str, network: list[str]
) -> tuple[subprocess.Popen[str], Path]:
    trace = folder / f"{tag}.jsonl"
    args = ["-m", "cfgplan", "run", str(DOMAIN), str(state), "--robot", name]
    args += ["--impl", str(EXAMPLE_IMPL), "--rate", "20", "--trace", str(trace)]
    args += ["--zenoh-config", str(hermetic_config(folder)), "--lease", "1", *network]
    return running.start(args, folder / f"{tag}.log"), trace


@pytest.mark.slow
@pytest.mark.parametrize("keyed", [False, True], ids=["open", "keys"])
def test_a_robot_of_another_problem_is_refused_alone(tmp_path: Path, keyed: bool) -> None:
    """Society A (step 2: Emil coordinates, Pippi helps) runs under the default
    society name (with keys: the keys' society, which the two problems
    share); Emil of society B (step 1, another problem) connects to it
    under the same name. B's Emil, which meets no robot of its own problem,
    stops with exit status 1 and a message naming both problems and
    --society; A's Emil, whose two robots had joined (one problem: one
    fingerprint) and whose goal was served, says B's Emil is not of his
    society and serves his goal on (before: both stopped, exit 1, and A's
    goal was lost). With keys, B's Emil runs without the switch protocol
    (--no-reconfigure) and refuses all the same."""
    port, other = free_port(), free_port()
    society = "default"
    if keyed:
        society = "shared"
        plan = plan_society(society, ["Emil", "Pippi"], (), ["Emil", "Pippi"])
        write_society(tmp_path / "keys", make_society(plan), force=False)
        keys = ["--keys", str(tmp_path / "keys")]
    else:
        keys = []
    with processes() as running:
        a_emil, a_trace = _robot(
            running, tmp_path, STEP2, "Emil", "a-emil", ["--listen", endpoint(port), *keys]
        )
        a_pippi, _ = _robot(
            running,
            tmp_path,
            STEP2,
            "Pippi",
            "a-pippi",
            ["--listen", endpoint(other), "--connect", endpoint(port), *keys],
        )
        wait_for(
            "A's Emil crosses the door with Pippi's help",
            first(
                a_trace,
                lambda r: (
                    r["event"] == "call"
                    and r.get("status") == "ran"
                    and r.get("functionality") == "cross-door"
                ),
            ),
            LIMIT,
        )
        b_network = ["--connect", endpoint(port), *keys]
        if keyed:  # no switch protocol: the transport itself ends the run
            b_network.append("--no-reconfigure")
        b_emil, _ = _robot(running, tmp_path, STEP1, "Emil", "b-emil", b_network)
        assert b_emil.wait(LIMIT) == 1
        refused = time.time()
        time.sleep(3.0)
        assert a_emil.poll() is None and a_pippi.poll() is None  # A goes on
    said = (tmp_path / "b-emil.log").read_text()
    assert f"society {society} runs two problems" in said
    assert "state-6.2.2-step1.lisp" in said and "state-6.2.2-step2.lisp" in said
    assert "this one, which met no robot of its own problem, stops" in said
    assert "--society NAME" in said and "Traceback" not in said
    said = (tmp_path / "a-emil.log").read_text()
    assert "robot Emil announces another problem" in said and "step1" in said
    events = read_trace(a_trace)
    assert not [r for r in events if r["event"] in ("switch", "stop")]
    served = [
        r
        for r in events
        if r["event"] == "call" and r["functionality"] == "cross-door" and r["status"] == "ran"
    ]
    assert [r for r in served if float(r["t"]) > refused + 1.0]  # type: ignore[arg-type]


def test_two_transports_of_different_problems_refuse_one_of_the_same_joins(
    tmp_path: Path,
) -> None:
    """In one process: Emil and Pippi announce one problem and see no conflict;
    a third session of another problem (its description long and full of
    characters that escape, clipped to fit a key) refuses alone, a lease
    after it saw them (it met no robot of its own problem): its poll raises,
    naming both problems, while nothing ends the run for it (no switch
    protocol). Emil and Pippi, who met each other, go on, and say once that
    the third is not of their society."""
    from cfgplan.runtime.errors import RunError
    from cfgplan.runtime.zenoh_transport import ZenohOptions, ZenohTransport

    config = str(hermetic_config(tmp_path))
    port = free_port()
    mine = _id(DOMAIN, STEP2)
    theirs = ProblemId("0123456789abcdef", "ü/é?#" * 100)

    def open_one(name: str, problem: ProblemId, listen: bool) -> ZenohTransport:
        where = (endpoint(port),) if listen else ()
        connect = () if listen else (endpoint(port),)
        options = ZenohOptions("t", where, connect, config, problem=problem)
        return ZenohTransport(name, options)

    emil = open_one("Emil", mine, True)
    pippi = open_one("Pippi", mine, False)
    try:
        time.sleep(1.0)
        emil.poll()
        pippi.poll()  # one problem: nothing raised
        said: list[str] = []
        emil.notices.append(lambda message, channel: said.append(message))
        other = open_one("Eve", theirs, False)
        try:

            def refused() -> dict[str, object] | None:
                with contextlib.suppress(RunError):
                    other.poll()  # a lease after it saw them, it refuses
                return {"c": other.conflict} if other.conflict else None

            wait_for("the conflict is seen", refused, LIMIT)
            with pytest.raises(RunError) as raised:
                other.poll()
            assert "society t runs two problems" in raised.value.message
            assert "0123456789abcdef" in raised.value.message
            assert mine.fingerprint in raised.value.message
            for transport in (emil, pippi):
                transport.poll()  # nothing raised: they met each other
                assert transport.conflict is None
            assert len(said) == 1 and "robot Eve announces another problem" in said[0]
        finally:
            other.close()
    finally:
        emil.close()
        pippi.close()


@pytest.mark.slow
def test_an_emitted_robot_program_announces_its_problem(tmp_path: Path) -> None:
    """The Pippi that ``cfgplan emit --lang python`` wrote for step 1 carries
    that problem's fingerprint (PROBLEM): connected to Emil of step 2 under
    the default society name, both refuse, naming both problems."""
    out = tmp_path / "emitted"
    emitted = subprocess.run(
        [sys.executable, "-m", "cfgplan", "emit", str(DOMAIN), str(STEP1), "-o", str(out)],
        capture_output=True,
        text=True,
        timeout=LIMIT,
    )
    assert emitted.returncode == 0, emitted.stderr
    assert _id(DOMAIN, STEP1).fingerprint in (out / "pippi.py").read_text()
    port = free_port()
    with processes() as running:
        emil, _ = _robot(running, tmp_path, STEP2, "Emil", "emil", ["--listen", endpoint(port)])
        args = [str(out / "pippi.py"), "--impl", str(EXAMPLE_IMPL), "--rate", "20"]
        args += ["--zenoh-config", str(hermetic_config(tmp_path)), "--lease", "1"]
        pippi = running.start([*args, "--connect", endpoint(port)], tmp_path / "pippi.log")
        assert pippi.wait(LIMIT) == 1
        assert emil.wait(LIMIT) == 1
    for tag in ("emil", "pippi"):
        said = (tmp_path / f"{tag}.log").read_text()
        assert "society default runs two problems" in said, tag
        assert "state-6.2.2-step1.lisp" in said and "state-6.2.2-step2.lisp" in said, tag
