"""``cfgplan launch``: a whole society in one command, one process per robot.

The slow tests launch cross-door step 2 (6.2.2) for real: the coordinator's
compass fails, the society switches 44 -> 47 and Emil keeps crossing; a
SIGTERM to the launch stops every robot; a robot that cannot start stops the
launch with a clear message. Every test checks by pid that no robot process
is left. Hermetic: loopback, free ports, scouting off (the launch's own
configuration), every wait bounded.
"""

from __future__ import annotations

import contextlib
import os
import re
import shlex
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from cfgplan.cli.root import click_command
from cfgplan.runtime.monitor import HOLD
from cfgplan.runtime.spawn import RobotCommand, again_args, commands, died, status_text
from tests.backends.support import DOMAINS, EXAMPLE_IMPL, ROOT
from tests.runtime.netutil import read_trace

STEP2 = [
    str(DOMAINS / "cross-door/domain.lisp"),
    str(DOMAINS / "cross-door/state-6.2.2-step2.lisp"),
]
LIMIT = 90.0  # seconds: three interpreters, Zenoh handshakes and a run, on a loaded machine


def _launch(*args: str, problem: list[str] = STEP2) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "cfgplan", "launch", *problem, *args],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )


def _pids(output: str) -> dict[str, int]:
    """The robots' pids, as the launch says them (``Emil  | (started: pid 123)``)."""
    return {
        m[1]: int(m[2]) for m in re.finditer(r"^(\w+) +\| \(started: pid (\d+)\)", output, re.M)
    }


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return False


def _follow(
    launched: subprocess.Popen[str],
) -> tuple[list[str], threading.Thread, Callable[[str, Callable[[], bool]], None]]:
    """The launch's output lines as they come (a reader thread), and
    ``until(what, found)``: wait for ``found`` at most :data:`LIMIT` s while
    the launch runs, else kill it and fail saying ``what`` and the output."""
    assert launched.stdout is not None
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(launched.stdout), daemon=True)  # type: ignore[arg-type]
    reader.start()

    def until(what: str, found: Callable[[], bool]) -> None:
        deadline = time.monotonic() + LIMIT
        while not found():
            if time.monotonic() > deadline or launched.poll() is not None:
                launched.kill()
                raise AssertionError(f"not seen: {what}\n{''.join(lines)}")
            time.sleep(0.05)

    return lines, reader, until


def _finish(process: subprocess.Popen[str]) -> tuple[int, str, str]:
    try:
        out, err = process.communicate(timeout=LIMIT)
    except subprocess.TimeoutExpired:
        process.kill()
        out, err = process.communicate(timeout=30)
        raise AssertionError(f"launch did not end within {LIMIT} s:\n{out}\n{err}") from None
    return process.returncode, out, err


def test_each_robot_listens_and_connects_to_every_robot_before_it() -> None:
    """The commands form a full mesh, the coordinator first and connected to nobody."""
    hosts = {"Emil": "10.0.0.1", "Pippi": "10.0.0.2", "Iris": "10.0.0.2"}
    ports = {"Emil": 7447, "Pippi": 7447, "Iris": 7448}
    made = commands(
        ["Emil", "Pippi", "Iris"],
        ["run", "d", "s"],
        {"Emil": ["--cycles", "9"]},
        hosts,
        ports,
        "Emil",
    )
    assert [c.robot for c in made] == ["Emil", "Pippi", "Iris"]
    assert made[0] == RobotCommand(
        "Emil",
        ("run", "d", "s", "--cycles", "9", "--robot", "Emil", "--listen", "tcp/10.0.0.1:7447"),
        "10.0.0.1",
        7447,
        coordinator=True,
    )
    assert made[2].args[-6:] == (
        "--listen",
        "tcp/10.0.0.2:7448",
        "--connect",
        "tcp/10.0.0.1:7447",
        "--connect",
        "tcp/10.0.0.2:7447",
    )
    assert status_text(-9) == "137 (SIGKILL)" and status_text(3) == "3"


def test_print_commands_writes_each_hosts_command(cfgplan) -> None:  # type: ignore[no-untyped-def]
    """Nothing starts; each robot's line has its endpoints, its faults and its trace."""
    done = cfgplan(
        "launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--print-commands", "--topology", "mesh",
        "--host", "Emil=10.0.0.1", "--host", "Pippi=10.0.0.2", "--duration", "5",
        "--inject", "fail compass(Pippi) at cycle 9", "--trace", "run.jsonl",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "# Emil on 10.0.0.1 (coordinator: start it first)"
    assert lines[2] == "# Pippi on 10.0.0.2"
    emil, pippi = lines[1], lines[3]
    assert emil.startswith("cfgplan run ") and "--duration 5" in emil and "--inject" not in emil
    assert "--robot Emil --listen tcp/10.0.0.1:7447" in emil and "--connect" not in emil
    assert "--inject 'fail compass(Pippi) at cycle 9'" in pippi and "--duration" not in pippi
    assert "--trace run-pippi.jsonl" in pippi
    assert pippi.endswith("--robot Pippi --listen tcp/10.0.0.2:7447 --connect tcp/10.0.0.1:7447")


def test_the_coordinator_serves_the_live_page_and_every_robot_records(cfgplan) -> None:  # type: ignore[no-untyped-def]
    """--live and --foxglove go to the coordinator only, --record FILE to every
    robot as FILE-NAME, --rate-allowance to every robot; a bad address is a
    usage error naming the option."""
    done = cfgplan(
        "launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--print-commands",
        "--host", "Emil=10.0.0.1", "--host", "Pippi=10.0.0.2", "--live", "0",
        "--foxglove", "127.0.0.1:8765", "--record", "run.mcap", "--rate-allowance", "3",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    (emil,) = [line for line in done.stdout.splitlines() if "--robot Emil" in line]
    (pippi,) = [line for line in done.stdout.splitlines() if "--robot Pippi" in line]
    assert "--live 0" in emil and "--foxglove 127.0.0.1:8765" in emil
    assert "--live" not in pippi and "--foxglove" not in pippi
    assert "--record run-emil.mcap" in emil and "--record run-pippi.mcap" in pippi
    assert "--rate-allowance 3" in emil and "--rate-allowance 3" in pippi
    bad = cfgplan("launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--live", "host:port")
    assert bad.returncode == 2 and "--live" in bad.stderr


@pytest.mark.slow
def test_robots_started_without_the_coordinator(cfgplan) -> None:  # type: ignore[no-untyped-def]
    """--robot Pippi alone (the coordinator, Emil, runs elsewhere): Pippi's
    command, marked as no coordinator's; options that go to the coordinator,
    or a fault aimed at a robot left out, are usage errors naming it (before:
    a KeyError traceback). Numbers go on exactly as written."""
    base = ["launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--robot", "Pippi"]
    shown = ["--print-commands", "--host", "Pippi=10.0.0.2"]
    unreached = cfgplan(*base, *shown)  # behind a router: which one?
    assert unreached.returncode == 2 and "give --router ENDPOINT" in unreached.stderr
    shown += ["--router", "tcp/10.0.0.1:7447"]
    done = cfgplan(*base, *shown, "--hold", "0.0000123456789", "--rate", "20.25")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[0] == "# Pippi on 10.0.0.2"
    assert done.stdout.splitlines()[1].endswith("--robot Pippi --router tcp/10.0.0.1:7447")
    assert "--hold 0.0000123456789 --rate 20.25" in done.stdout
    late = cfgplan(*base, *shown, "--duration", "86400.25")
    assert late.returncode == 2 and "the coordinator, Emil" in late.stderr
    assert "Traceback" not in late.stderr
    aimed = cfgplan(*base, *shown, "--inject", "fail compass(Emil) at cycle 9")
    assert aimed.returncode == 2 and "aims at Emil" in aimed.stderr
    typo = cfgplan(*base, *shown, "--inject", "kill Emli at cycle 9")
    assert typo.returncode == 2 and "no robot Emli in this society" in typo.stderr
    assert "did you mean Emil?" in typo.stderr and not typo.stdout


def test_run_options_reach_every_robot_as_written(cfgplan) -> None:  # type: ignore[no-untyped-def]
    """Every option of cfgplan run given to launch goes to each robot's command
    word for word, in its order: also those equal to run's defaults, numbers
    as written, and options launch never declared. Before, launch parsed its
    own copies of run's options and wrote them out again: --rate 10.0 and
    --rank 1 were dropped (run's defaults), --hold 0.50 became 0.5, and
    --ros2-via or --use-sim-time were no options of launch."""
    passed = ["--rate", "10.0", "--rank", "1", "--hold", "0.50", "--stale-periods=3", "--ros2",
              "--ros2-via", "zenoh", "--use-sim-time", "--society", "lab"]  # fmt: skip
    done = cfgplan(
        "launch", *STEP2, "--impl", str(EXAMPLE_IMPL), *passed, "--print-commands",
        "--host", "Emil=10.0.0.1", "--host", "Pippi=10.0.0.2", "--trace=run.jsonl",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    robots = [line for line in done.stdout.splitlines() if line.startswith("cfgplan run ")]
    assert len(robots) == 2
    for line, name in zip(robots, ("emil", "pippi"), strict=True):
        words = shlex.split(line)
        assert words[2:6] == [*STEP2, "--impl", str(EXAMPLE_IMPL)]
        assert words[6 : 6 + len(passed)] == passed, line
        assert f"--trace run-{name}.jsonl" in line


def test_launch_leaves_runs_options_and_their_defaults_to_run(cfgplan) -> None:  # type: ignore[no-untyped-def]
    """launch declares only its own options (and --robot and --router, which it
    sets for each robot): no copy of run's, so no default of its own. Before,
    it re-declared some 30 of them, --hold with a default (none) that was not
    run's. A robot started without --hold holds run's default."""
    launch, run = click_command("launch"), click_command("run")
    flags = {f for p in launch.params for f in (*p.opts, *p.secondary_opts) if f.startswith("--")}
    runs = {f for p in run.params for f in (*p.opts, *p.secondary_opts) if f.startswith("--")}
    assert flags & runs == {"--robot", "--router"}
    done = cfgplan(
        "launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--print-commands",
        "--host", "Emil=10.0.0.1", "--host", "Pippi=10.0.0.2",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    (line, *_) = [line for line in done.stdout.splitlines() if line.startswith("cfgplan run ")]
    assert "--hold" not in line
    assert run.make_context("run", shlex.split(line)[2:]).params["hold"] == HOLD


@pytest.mark.parametrize(
    ("mistake", "said"),
    [
        (["--hodl", "2"], "No such option: --hodl"),
        (["--hold", "-1"], "Invalid value for '--hold': -1: must be more than 0"),
        (["--use-sim-time"], "says how --ros2 and --ros2-map speak ROS 2: give one of them"),
        (["--ros2", "--ros2-via", "dds"], "'dds': give rclpy or zenoh"),
        (["--listen", "tcp/127.0.0.1:7447"], "launch gives each robot its endpoints"),
    ],
    ids=["misspelt", "bad-value", "needs-another", "bad-choice", "launchs-own"],
)
def test_a_mistaken_run_option_is_a_usage_error_before_anything_starts(  # type: ignore[no-untyped-def]
    cfgplan, mistake: list[str], said: str
) -> None:
    """Run's own command parses the options launch passes on, with run's
    checks and words, before any robot starts: exit 2 under launch's usage.
    Before, launch knew only its copies of them: --use-sim-time and --ros2-via
    were "no such option", and run's checks of them were never made."""
    done = cfgplan("launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--duration", "3", *mistake)
    assert done.returncode == 2, done.stdout + done.stderr
    assert said in done.stderr
    assert done.stderr.startswith("Usage: cfgplan launch [OPTIONS] DOMAIN STATE")
    assert "started: pid" not in done.stdout and "Traceback" not in done.stderr
    if mistake[0] == "--hodl":
        assert "--hold" in done.stderr  # the did-you-mean draws on run's options


def test_print_commands_behind_a_router_start_it_on_the_coordinators_host(cfgplan) -> None:  # type: ignore[no-untyped-def]
    """The default topology: the router first, on the
    coordinator's host (every interface, Zenoh's port, the robots' lease),
    then each robot a client of it, listening nowhere; --router names one
    that runs already (none is printed)."""
    base = ["launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--print-commands"]
    hosts = ["--host", "Emil=10.0.0.1", "--host", "Pippi=10.0.0.2"]
    done = cfgplan(*base, *hosts, "--lease", "3")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[:2] == [
        "# the router on 10.0.0.1 (start it first)",
        "cfgplan router --listen tcp/0.0.0.0:7447 --lease 3",
    ]
    assert lines[2] == "# Emil on 10.0.0.1 (coordinator)" and lines[4] == "# Pippi on 10.0.0.2"
    for robot, line in (("Emil", lines[3]), ("Pippi", lines[5])):
        assert line.endswith(f"--robot {robot} --router tcp/10.0.0.1:7447"), line
        assert "--listen" not in line and "--connect" not in line
    given = cfgplan(*base, *hosts, "--router", "tcp/10.0.0.9:7447")
    assert given.returncode == 0, given.stderr
    assert "cfgplan router" not in given.stdout
    assert given.stdout.count("--router tcp/10.0.0.9:7447") == 2
    mixed = cfgplan(*base, *hosts, "--router", "tcp/10.0.0.9:7447", "--topology", "mesh")
    assert mixed.returncode == 2 and "--router" in mixed.stderr
    wrong = cfgplan(*base, *hosts, "--topology", "star")
    assert wrong.returncode == 2 and "'star' is not a topology" in wrong.stderr


def test_print_commands_with_keys_start_the_societys_secured_router(  # type: ignore[no-untyped-def]
    cfgplan, tmp_path: Path
) -> None:
    """With --keys the robots are clients of a router too (before: a mesh,
    a router being none of the society's keys): the society's own router,
    started with the keys (its certificate is among them) and listening on TLS,
    and every robot its client over TLS with its own keys; keys as written.
    Keys without a router's certificate (made before routers had one) are
    refused before anything starts, saying how to make them; --router names
    a secured router that runs already."""
    from cfgplan.security.keys import make_society, plan_society, write_society

    keys, old = society_keys(tmp_path / "keys", "lab", "Emil", "Pippi"), tmp_path / "old"
    write_society(old, make_society(plan_society("lab", ["Emil", "Pippi"], (), ["Emil"])), False)
    base = ["launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--print-commands"]
    hosts = ["--host", "Emil=10.0.0.1", "--host", "Pippi=10.0.0.2"]
    done = cfgplan(*base, *hosts, "--keys", str(keys))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[:2] == [
        "# the router on 10.0.0.1 (start it first)",
        f"cfgplan router --listen tls/0.0.0.0:7447 --keys {keys}",
    ]
    for robot, line in (("Emil", lines[3]), ("Pippi", lines[5])):
        assert line.endswith(f"--robot {robot} --router tls/10.0.0.1:7447"), line
        assert f"--keys {keys}" in line and "--listen" not in line and "--connect" not in line
    refused = cfgplan(*base, *hosts, "--keys", str(old))
    assert refused.returncode == 1 and "no certificate for a router" in refused.stderr
    assert "cfgplan keys new" in refused.stderr and "Traceback" not in refused.stderr
    given = cfgplan(*base, *hosts, "--keys", str(old), "--router", "tls/10.0.0.9:7447")
    assert given.returncode == 0, given.stderr
    assert given.stdout.count("--router tls/10.0.0.9:7447") == 2
    mesh = cfgplan(*base, *hosts, "--keys", str(old), "--topology", "mesh")
    assert mesh.returncode == 0 and "cfgplan router" not in mesh.stdout


def test_print_commands_needs_every_host(cfgplan) -> None:  # type: ignore[no-untyped-def]
    done = cfgplan(
        "launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--print-commands", "--host", "Emil=a"
    )
    assert done.returncode == 2 and "give the host of Pippi" in done.stderr


def test_an_unknown_robot_is_refused_before_anything_starts(cfgplan) -> None:  # type: ignore[no-untyped-def]
    done = cfgplan("launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--robot", "Bob")
    assert done.returncode == 1
    assert "no robot Bob in" in done.stderr and "(its robots: Pippi, Emil)" in done.stderr
    assert "Traceback" not in done.stderr and "started: pid" not in done.stdout


def test_a_wrong_ros2_map_is_refused_before_anything_starts(cfgplan, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    """The map is checked once against the domain, with its file and line; no robot starts."""
    pytest.importorskip("rosbags")
    data = ROOT / "tests" / "ros2" / "data"
    bad = tmp_path / "map.toml"
    bad.write_text('[[bind]]\nfunctionality = "laser"\noutput = "scans"\ntopic = "/scan"\n'
                   'type = "sensor_msgs/msg/LaserScan"\n')  # fmt: skip
    done = cfgplan(
        "launch", str(data / "drive.lisp"), str(data / "drive-state.lisp"),
        "--impl", str(data / "drive_impl.py"), "--ros2-map", str(bad),
    )  # fmt: skip
    assert done.returncode == 1
    assert f"{bad}:3:1: error: laser has no output 'scans'" in done.stderr
    assert "started: pid" not in done.stdout


def test_host_without_print_commands_is_a_usage_error(cfgplan) -> None:  # type: ignore[no-untyped-def]
    done = cfgplan("launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--host", "Emil=10.0.0.1")
    assert done.returncode == 2 and "give --print-commands" in done.stderr


def test_a_port_in_use_is_refused(cfgplan) -> None:  # type: ignore[no-untyped-def]
    """Someone listens on the --port (the router's; in a mesh the
    coordinator's): a clear error, no robot started."""
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        base = ["launch", *STEP2, "--impl", str(EXAMPLE_IMPL), "--port", str(port)]
        done = cfgplan(*base)  # behind a router: the router's port
        mesh = cfgplan(*base, "--topology", "mesh")  # the coordinator's
    assert done.returncode == 1 and mesh.returncode == 1
    assert f"port {port} on 127.0.0.1 is in use: router cannot listen on it" in done.stderr
    assert f"port {port} on 127.0.0.1 is in use: Emil cannot listen on it" in mesh.stderr
    assert "started: pid" not in done.stdout + mesh.stdout


@pytest.mark.slow
def test_launch_runs_cross_door_switches_and_leaves_no_process(tmp_path: Path) -> None:
    """Step 2 launched in one command: Emil's compass fails at cycle 40, the society
    switches 44 -> 47 across the two processes, cross-door runs again after it, the
    launch exits 0 when Emil's --duration ends, and both pids are gone."""
    trace = tmp_path / "run.jsonl"
    launched = _launch(
        "--impl", str(EXAMPLE_IMPL), "--rate", "20", "--duration", "8",
        "--inject", "fail compass(Emil) at cycle 40", "--trace", str(trace),
    )  # fmt: skip
    code, out, err = _finish(launched)
    pids = _pids(out)
    assert code == 0, f"{out}\n{err}"
    assert list(pids) == ["router", "Emil", "Pippi"], out  # the router, then the coordinator
    assert all(_gone(pid) for pid in pids.values()), out
    mine = read_trace(tmp_path / "run-emil.jsonl")
    theirs = read_trace(tmp_path / "run-pippi.jsonl")
    switch = next(r for r in mine if r["event"] == "switch")
    assert (switch["from_cost"], switch["to_cost"]) == (44, 47)
    assert [r["id"] for r in theirs if r["event"] == "install"][-1] == switch["id"]
    served = [
        r
        for r in mine
        if r["event"] == "call"
        and r["functionality"] == "cross-door"
        and r["status"] == "ran"
        and int(r["cycle"]) > int(switch["cycle"])  # type: ignore[call-overload]
    ]
    assert served, "cross-door never ran after the switch"
    assert re.search(r"^Emil +\| .*switch 1 \(compass\(Emil\) failed\): cost 44 -> 47", out, re.M)
    assert "Traceback" not in out + err


@pytest.mark.slow
def test_sigterm_to_launch_stops_every_robot() -> None:
    """No limit given: the robots run until the launch gets SIGTERM; then it stops
    them (coordinator first), exits 0 (Emil's status) and no pid is left."""
    launched = _launch("--impl", str(EXAMPLE_IMPL), "--rate", "20")
    assert launched.stdout is not None
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(launched.stdout), daemon=True)  # type: ignore[arg-type]
    reader.start()
    deadline = time.monotonic() + LIMIT
    while "Emil: robot Pippi seen" not in "".join(lines) and time.monotonic() < deadline:
        assert launched.poll() is None, "".join(lines)
        time.sleep(0.05)
    seen = "".join(lines)
    if "Emil: robot Pippi seen" not in seen:
        launched.kill()
    assert "Emil: robot Pippi seen" in seen, seen
    pids = _pids(seen)
    launched.send_signal(signal.SIGTERM)
    try:
        launched.wait(LIMIT)
    finally:
        if launched.poll() is None:
            launched.kill()
    reader.join(10.0)
    out, err = "".join(lines), launched.stderr.read() if launched.stderr else ""
    assert launched.returncode == 0, f"{out}\n{err}"
    assert sorted(pids) == ["Emil", "Pippi", "router"]
    assert all(_gone(pid) for pid in pids.values())
    assert "Traceback" not in out + err


@pytest.mark.slow
def test_a_robot_that_cannot_start_stops_the_launch(tmp_path: Path) -> None:
    """Pippi's implementations lack measure-door, which her part of 44 runs: she exits
    1, the launch says why, stops Emil and exits 1; no pid is left."""
    partial = tmp_path / "partial.py"
    partial.write_text(
        textwrap.dedent(
            f"""
            from pathlib import Path
            from cfgplan.runtime import Implementation, load_module
            _base = load_module(Path({str(EXAMPLE_IMPL)!r}))
            globals().update(
                {{k: v for k, v in vars(_base).items() if isinstance(v, Implementation)
                  and v.name != "measure-door"}}
            )
            """
        )
    )
    code, out, err = _finish(_launch("--impl", str(partial), "--rate", "20"))
    pids = _pids(out)
    assert code == 1, f"{out}\n{err}"
    assert "Pippi stopped (exit status 1)" in err and "measure-door" in err, err
    assert list(pids) == ["router", "Emil", "Pippi"]
    assert all(_gone(pid) for pid in pids.values())
    assert "Traceback" not in out + err


def test_a_robot_started_again_keeps_its_command_but_its_files_and_faults() -> None:
    """A start again runs the same command (name, port, endpoints) with a trace
    and a recording of its own (the dead process's are kept) and without the
    scripted faults (the new process would count its cycles from 0 and meet
    them again)."""
    args = ("run", "d.lisp", "s.lisp", "--trace", "/tmp/run-pippi.jsonl", "--inject",
            "kill Pippi at cycle 5", "--record", "out/pippi", "--robot", "Pippi",
            "--listen", "tcp/127.0.0.1:7447")  # fmt: skip
    assert again_args(args, 3) == (
        "run", "d.lisp", "s.lisp", "--trace", "/tmp/run-pippi-3.jsonl", "--record",
        "out/pippi-3", "--robot", "Pippi", "--listen", "tcp/127.0.0.1:7447",
    )  # fmt: skip


def test_what_counts_as_a_death() -> None:
    """Killed or crashed: started again; a run or task done (0), a robot that
    could not start or was refused (1, 2), the coordinator out of
    configurations (3): not (it would end the same way)."""
    assert [died(c, False) for c in (-9, 137, 0, 1, 2, 3)] == [
        True,
        True,
        False,
        False,
        False,
        True,
    ]
    assert [died(c, True) for c in (-9, 137, 0, 1, 2, 3)] == [
        True,
        True,
        False,
        False,
        False,
        False,
    ]


def _newest_pid(output: str, robot: str) -> int | None:
    found = re.findall(rf"^{robot} +\| \(started(?: again)?: pid (\d+)", output, re.M)
    return int(found[-1]) if found else None


@pytest.mark.slow
def test_respawn_starts_a_killed_robot_again_and_the_society_takes_it_back(
    tmp_path: Path,
) -> None:
    """--respawn: Pippi's process is killed (SIGKILL) three times, each new one
    soon after it started: the launch says each death and starts her again
    after 1 s, 2 s, then 4 s (each death in a row doubles the delay), each
    start writing a trace of its own. After the third, the society serves
    the goal again with her fourth process (it runs its part, Emil crosses
    on her data). Then Emil, the coordinator, is killed: started again, he
    takes his society back and serves the goal; SIGTERM then stops every
    robot, exit 0, no pid left.
    Before, a dead robot stayed dead: --respawn did not exist."""
    trace = tmp_path / "run.jsonl"
    launched = _launch(
        "--impl", str(EXAMPLE_IMPL), "--rate", "20", "--respawn", "--trace", str(trace)
    )  # fmt: skip
    lines, reader, until = _follow(launched)

    try:
        until("Emil sees Pippi", lambda: "Emil: robot Pippi seen" in "".join(lines))
        pids = [_pids("".join(lines))["Pippi"]]
        for life in (2, 3, 4):
            os.kill(pids[-1], signal.SIGKILL)
            until(f"start {life}", lambda life=life: f"start {life})" in "".join(lines))  # type: ignore[misc]
            pid = _newest_pid("".join(lines), "Pippi")
            assert pid is not None and pid != pids[-1]
            pids.append(pid)
            mine = tmp_path / f"run-pippi-{life}.jsonl"
            until(f"life {life} runs", lambda mine=mine: bool(read_trace(mine)))  # type: ignore[misc]
        again = time.time()
        fourth = tmp_path / "run-pippi-4.jsonl"

        def served() -> bool:
            crossed = [
                r
                for r in read_trace(tmp_path / "run-emil.jsonl")
                if r["event"] == "call"
                and r["functionality"] == "cross-door"
                and r["status"] == "ran"
                and float(r["t"]) > again  # type: ignore[arg-type]
            ]
            helped = [
                r for r in read_trace(fourth) if r["event"] == "call" and r["status"] == "ran"
            ]
            return bool(crossed and helped)

        until("the goal served with Pippi's fourth process", served)
        emil = _pids("".join(lines))["Emil"]
        os.kill(emil, signal.SIGKILL)  # the coordinator too: started again, it takes it back
        again_at = re.compile(r"^Emil +\| \(started again", re.M)
        until("Emil started again", lambda: bool(again_at.search("".join(lines))))

        def taken_back() -> bool:
            crossed = read_trace(tmp_path / "run-emil-2.jsonl")
            return any(
                r["event"] == "call" and r["functionality"] == "cross-door" and r["status"] == "ran"
                for r in crossed
            )

        until("Emil's second process serves the goal", taken_back)
        launched.send_signal(signal.SIGTERM)
        launched.wait(LIMIT)
    finally:
        if launched.poll() is None:
            launched.kill()
    reader.join(10.0)
    out, err = "".join(lines), launched.stderr.read() if launched.stderr else ""
    assert launched.returncode == 0, f"{out}\n{err}"
    delays = re.findall(r"^Pippi +\| \(died, exit status 137 .*started again in (\S+) s", out, re.M)
    assert delays == ["1", "2", "4"], out
    emils = [int(p) for p in re.findall(r"^Emil +\| \(started(?: again)?: pid (\d+)", out, re.M)]
    assert len(emils) == 2 and emils[0] == emil, out
    assert all(_gone(pid) for pid in [*pids, *emils])
    assert "Traceback" not in out + err


@pytest.mark.slow
def test_a_sequence_whose_coordinator_is_killed_is_taken_over_and_served_to_its_end(
    tmp_path: Path,
) -> None:
    """The 6.2.2 sequence launched with --respawn: Pippi, who owns the first
    goal and coordinates, is killed (SIGKILL) while her crossing is served.
    Emil, next in the order of succession, takes over within the lease and
    1 s; the launch starts Pippi again 1 s later, she steps down and follows
    him, and the sequence is served to its end under his coordination: both
    crossings, every robot told, the launch ends by itself, exit 0, no pid
    left. Before, nobody took over: Emil waited, stopped, for Pippi started
    again to take her society back."""
    from cfgplan.runtime.zenoh_config import DEFAULT_LEASE
    from tests.reconfigure.test_sequence_network import SEQUENCE, STEPS

    trace = tmp_path / "run.jsonl"
    launched = _launch(
        "--impl", str(STEPS), "--rate", "20", "--respawn", "--trace", str(trace), problem=SEQUENCE
    )  # fmt: skip
    lines, reader, until = _follow(launched)
    emil_trace, again = tmp_path / "run-emil.jsonl", tmp_path / "run-pippi-2.jsonl"

    def seen(path: Path, event: str, **fields: object) -> Callable[[], bool]:
        return lambda: any(
            r["event"] == event and all(r.get(k) == v for k, v in fields.items())
            for r in read_trace(path)
        )

    try:
        crossing = {"functionality": "cross-door", "status": "ran"}
        until("Pippi's crossing served", seen(tmp_path / "run-pippi.jsonl", "call", **crossing))
        pippi = _pids("".join(lines))["Pippi"]
        killed = time.time()
        os.kill(pippi, signal.SIGKILL)
        until("Emil takes over", seen(emil_trace, "takeover"))
        until("Pippi started again steps down", seen(again, "step-down", leader="Emil"))
        launched.wait(LIMIT)
    finally:
        if launched.poll() is None:
            launched.kill()
    reader.join(10.0)
    out, err = "".join(lines), launched.stderr.read() if launched.stderr else ""
    assert launched.returncode == 0, f"{out}\n{err}"
    emil = read_trace(emil_trace)
    (takeover,) = [r for r in emil if r["event"] == "takeover"]
    assert (takeover["after"], takeover["step"]) == ("Pippi", 0)
    assert float(takeover["t"]) - killed < DEFAULT_LEASE + 1.0  # type: ignore[arg-type]
    after = [r["event"] for r in emil if r["event"] in ("achieved", "finish")]
    assert after == ["achieved", "achieved", "finish"], after
    (finish,) = [r for r in read_trace(again) if r["event"] == "finish"]
    assert finish["from"] == "Emil"
    assert re.search(r"^Pippi +\| \(died, exit status 137", out, re.M), out
    assert all(_gone(pid) for pid in _pids(out).values())
    assert "Traceback" not in out + err


def _connections(pid: int) -> list[int]:
    """The remote ports of ``pid``'s established TCP connections (from /proc)."""
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        with contextlib.suppress(OSError):
            target = os.readlink(fd)
            if target.startswith("socket:["):
                inodes.add(target[8:-1])
    ports = []
    for table in ("tcp", "tcp6"):
        for line in Path(f"/proc/{pid}/net/{table}").read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] == "01" and fields[9] in inodes:  # ESTABLISHED, this process's
                ports.append(int(fields[2].rsplit(":", 1)[1], 16))
    return sorted(ports)


def cross_door_served(trace: Path, t: float) -> Callable[[], bool]:
    """Whether Emil's cross-door, in ``trace``, ran on Pippi's data after ``t`` (time.time())."""

    def served() -> bool:
        return any(
            r["event"] == "call"
            and r["functionality"] == "cross-door"
            and r["status"] == "ran"
            and float(r["t"]) > t  # type: ignore[arg-type]
            and r["inputs"]
            for r in read_trace(trace)
        )

    return served


def society_keys(folder: Path, society: str, *robots: str) -> Path:
    """The keys of ``robots`` (the first coordinates) and the society's router, in ``folder``."""
    from cfgplan.security.keys import make_society, plan_society, write_society

    plan = plan_society(society, robots, (), robots[:1], ["router"])
    write_society(folder, make_society(plan), force=False)
    return folder


@pytest.mark.slow
@pytest.mark.parametrize("keyed", [False, True], ids=["open", "keys"])
def test_behind_a_router_each_robot_holds_one_connection_and_outlives_the_routers_death(
    tmp_path: Path, keyed: bool
) -> None:
    """The default topology: launch starts a router, then every robot as its
    client: each robot's only connection is to the router's port (in a mesh,
    robot k holds one to each of the k-1 before it and more to it). The
    router is killed (SIGKILL): the robots see each other lost; --respawn
    starts the router again on its port after 1 s, the clients reconnect by
    themselves, and the coordinator serves the goal again with Pippi's data.
    SIGTERM then stops every process, the router last; no pid is left. With
    the society's keys, the same through its secured router (listening on
    TLS, started again with its keys; before: with --keys launch made a mesh)."""
    trace = tmp_path / "run.jsonl"
    keys = ["--keys", str(society_keys(tmp_path / "keys", "lab", "Emil", "Pippi"))] if keyed else []
    launched = _launch(
        "--impl", str(EXAMPLE_IMPL), "--rate", "20", "--respawn", "--trace", str(trace), *keys
    )  # fmt: skip
    lines, reader, until = _follow(launched)
    protocol = "tls" if keyed else "tcp"
    listening = re.compile(
        rf"^router +\| router \w+ listening on {protocol}/127\.0\.0\.1:(\d+)", re.M
    )
    emil = tmp_path / "run-emil.jsonl"

    try:
        until("Emil sees Pippi", lambda: "Emil: robot Pippi seen" in "".join(lines))
        # The router says it listens once its session is open; its clients may connect
        # and meet before its line reaches launch's output (by a thread of its own).
        until("the router says it listens", lambda: bool(listening.findall("".join(lines))))
        pids = _pids("".join(lines))
        port = int(listening.findall("".join(lines))[0])
        for robot in ("Emil", "Pippi"):
            until(f"{robot} connected", lambda r=robot: _connections(pids[r]) == [port])  # type: ignore[misc]
        until("the goal served", cross_door_served(emil, 0.0))
        killed = time.time()
        os.kill(pids["router"], signal.SIGKILL)
        until("Emil sees Pippi lost", lambda: "Emil: robot Pippi lost" in "".join(lines))
        until("the router again", lambda: "router | (started again" in "".join(lines))
        until("the goal served again", cross_door_served(emil, killed + 1.0))
        until("the router listens again", lambda: len(listening.findall("".join(lines))) == 2)
        router = _newest_pid("".join(lines), "router")
        assert router is not None and router != pids["router"]
        launched.send_signal(signal.SIGTERM)
        launched.wait(LIMIT)
    finally:
        if launched.poll() is None:
            launched.kill()
    reader.join(10.0)
    out, err = "".join(lines), launched.stderr.read() if launched.stderr else ""
    assert launched.returncode == 0, f"{out}\n{err}"
    assert re.search(r"^router +\| \(died, exit status 137 .*started again in 1 s", out, re.M), out
    assert all(_gone(pid) for pid in [*pids.values(), router])
    assert "Traceback" not in out + err
