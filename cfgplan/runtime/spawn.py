"""A whole society started on this machine, one process per robot (``cfgplan launch``).

Each robot (and device) of a state runs its own ``cfgplan run --robot NAME``
process, as each ran on its own body in the thesis (5.2.2), here side by side
for development and demos (like ``ros2 launch`` or ``docker compose up``):

* :func:`commands` writes the command of each robot, the coordinator (the
  goal's robot, 5.5) first. Behind a router (:func:`router_command`,
  :mod:`cfgplan.runtime.router`) each robot is its client (``--router``):
  one connection each. In a mesh, robot *k* listens on its own endpoint and
  connects to the endpoints of robots 1 to *k*-1, so every two robots share
  a link without scouting (N·(N−1)/2 links; Zenoh peers do not route for
  each other);
* :class:`Launch` starts them in that order — the router first, then every
  robot at once; in a mesh each robot once the previous one listens (its
  port accepts a connection) — prefixes every line of their
  output with the robot's name (in colour on a terminal), and stops them all
  by pid: SIGTERM, a bounded wait (:attr:`SpawnOptions.stop_wait`), then
  SIGKILL.

When the coordinator ends, the run is over: the others are stopped (the
router last), and the
launch's exit status is the coordinator's (0 ran, 1 a user error or a failing
functionality, 3 no configuration left). A robot that exits with 1 or 2 (it
could not start or run its part) stops the launch: exit status 1, with the
robot's last lines. Any other end of a robot (a scripted ``kill``, a crash) is
the society's business: the coordinator sees it lost and reconfigures. The
router that ends cuts the robots off from each other: without ``--respawn``
the launch stops (exit status 1).

With :attr:`SpawnOptions.respawn` (``--respawn``) a robot whose process died —
killed, crashed: any end but those above (:func:`died`) — is started again,
the coordinator too, after 1 s, twice as long with each death in a row (at
most 30 s), a process that ran 10 s counting as the first death again; the
output says each death and each start again. The society takes the new
process back as it takes any robot back (the coordinator started again takes
its society back).
"""

from __future__ import annotations

import contextlib
import os
import shlex
import signal
import socket
import subprocess
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, TextIO

from cfgplan.runtime.errors import RunError
from cfgplan.runtime.options import LAUNCHED

__all__ = [
    "STYLES",
    "Launch",
    "RobotCommand",
    "SpawnOptions",
    "again_args",
    "backoff",
    "commands",
    "death_text",
    "died",
    "free_port",
    "in_use",
    "router_command",
    "status_text",
    "supervise",
]

USER_ERRORS = (1, 2)
"""Exit statuses of a robot that could not start or run its part (user error, usage)."""

STYLES = ("cyan", "magenta", "green", "yellow", "blue", "red")
"""The colours of the robots' prefixes on a terminal, in launch order (rich style names)."""


@dataclass(frozen=True)
class SpawnOptions:
    """How robots are started and stopped."""

    start_timeout: float = 60.0
    """Seconds a robot may take to listen (an interpreter, the planner, a Zenoh session)."""
    stop_wait: float = 10.0
    """Seconds the robots have to stop after SIGTERM before they are killed."""
    poll: float = 0.05
    """Seconds between two looks at the processes."""
    tail: int = 20
    """Lines of a robot's output kept to say why it failed."""
    colour: bool | None = None
    """Colour the prefixes; ``None``: when the output is a terminal and NO_COLOR is unset."""
    respawn: bool = False
    """Start a robot whose process died again (``--respawn``; see :class:`Launch`)."""
    respawn_delay: float = 1.0
    """Seconds before the first start again; doubled with each death in a row."""
    respawn_most: float = 30.0
    """The longest wait before a start again."""
    respawn_reset: float = 10.0
    """Seconds a process must have run for its death not to count as one more in a row."""


@dataclass(frozen=True)
class RobotCommand:
    """One robot's process: ``cfgplan run ... --robot NAME`` with its endpoints."""

    robot: str
    args: tuple[str, ...]
    """The command line after the program (``run DOMAIN STATE ...``)."""
    host: str
    port: int
    """Where it listens (0: nowhere, a client of the router)."""
    coordinator: bool = False
    router: bool = False
    """The society's router (``cfgplan router``), not a robot."""

    @property
    def listens(self) -> bool:
        return self.port > 0

    def shell(self, program: Sequence[str] = ("cfgplan",)) -> str:
        """The command as a shell line."""
        return shlex.join([*program, *self.args])


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port on ``host`` that nobody listens on right now (bound to port 0)."""
    with socket.socket() as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def in_use(port: int, host: str = "127.0.0.1") -> bool:
    """Whether ``port`` on ``host`` cannot be listened on now."""
    with socket.socket() as s:
        try:
            s.bind((host, port))
        except OSError:
            return True
    return False


def endpoint(host: str, port: int) -> str:
    """A Zenoh TCP endpoint; an IPv6 address in brackets."""
    return f"tcp/[{host}]:{port}" if ":" in host else f"tcp/{host}:{port}"


def commands(
    robots: Sequence[str],
    common: Sequence[str],
    extra: Mapping[str, Sequence[str]],
    hosts: Mapping[str, str],
    ports: Mapping[str, int],
    coordinator: str | None = None,
    router: str | None = None,
) -> list[RobotCommand]:
    """The command of each of ``robots`` (the ``coordinator`` first, if it is
    one of them): ``common`` (``run DOMAIN STATE --impl ...``), then its
    ``extra`` options, ``--robot``, and with a ``router`` endpoint
    ``--router`` it (``ports`` are not used); else ``--listen`` on its host and
    port and ``--connect`` to every robot before it (a mesh)."""
    out: list[RobotCommand] = []
    for k, robot in enumerate(robots):
        args = [*common, *extra.get(robot, ()), "--robot", robot]
        if router is not None:
            args += ["--router", router]
        else:
            args += ["--listen", endpoint(hosts[robot], ports[robot])]
            for earlier in robots[:k]:
                args += ["--connect", endpoint(hosts[earlier], ports[earlier])]
        port = 0 if router is not None else ports[robot]
        out.append(RobotCommand(robot, tuple(args), hosts[robot], port, robot == coordinator))
    return out


def router_command(
    host: str, port: int, listen: str, lease: float | None, keys: str | None = None
) -> RobotCommand:
    """The society's router (``cfgplan router``), listening on ``listen``
    (reached at ``host``:``port``), with the robots' ``lease`` if one is given
    and, with the society's ``keys``, secured (its certificate is among them)."""
    args = ["router", "--listen", listen]
    if lease is not None:
        args += ["--lease", f"{lease:g}"]
    if keys is not None:
        args += ["--keys", keys]
    return RobotCommand("router", tuple(args), host, port, router=True)


def backoff(options: SpawnOptions, lived: float, deaths: int) -> tuple[int, float]:
    """A process that ran ``lived`` seconds died after ``deaths`` deaths in a
    row: the deaths in a row now, and the seconds to wait before starting it
    again (:attr:`SpawnOptions.respawn_delay`, doubled with each death in a
    row, at most :attr:`SpawnOptions.respawn_most`; a process that ran
    :attr:`SpawnOptions.respawn_reset` seconds counts as the first death)."""
    deaths = 1 if lived >= options.respawn_reset else deaths + 1
    return deaths, min(options.respawn_delay * 2 ** (deaths - 1), options.respawn_most)


def death_text(code: int, lived: float, deaths: int, delay: float) -> str:
    """What the console says of a death and the start again it waits for."""
    row = f"death {deaths} in a row" if deaths > 1 else "its first death in a row"
    return (
        f"(died, exit status {status_text(code)}, after {lived:.1f} s: started again in "
        f"{delay:g} s, {row})"
    )


def supervise(
    argv: Sequence[str],
    options: SpawnOptions | None = None,
    say: Callable[[str], None] | None = None,
) -> int:
    """Run ``argv`` (a program and its arguments) and start it again each
    time it dies (:func:`died`, as a coordinator: 0, 1, 2 and 3 end the run),
    after :func:`backoff`'s delay, with a trace and recording of its own
    and without scripted faults (:func:`again_args`): ``run_all.py
    --respawn``. SIGINT or SIGTERM stops the process running (SIGTERM) and
    ends the supervision; its exit status is returned."""
    options = options or SpawnOptions(respawn=True)
    tell = say or (lambda line: print(line, file=sys.stderr, flush=True))
    program, args = argv[0], tuple(argv[1:])
    stop = threading.Event()
    child: list[subprocess.Popen[bytes]] = []
    previous: dict[int, Any] = {}

    def handler(signum: int, frame: object) -> None:
        stop.set()
        for process in child[-1:]:
            with contextlib.suppress(ProcessLookupError):
                process.send_signal(signal.SIGTERM)

    if threading.current_thread() is threading.main_thread():
        for signum in (signal.SIGINT, signal.SIGTERM):
            previous[signum] = signal.signal(signum, handler)
    try:
        life, deaths = 1, 0
        while True:
            began = time.monotonic()
            process = subprocess.Popen(
                [program, *(args if life == 1 else again_args(args, life))],
                preexec_fn=_death_signal(),
            )
            child.append(process)
            tell(f"(started: pid {process.pid}" + (f", start {life})" if life > 1 else ")"))
            code = process.wait()
            if stop.is_set() or not died(code, coordinator=True):
                return code if code >= 0 else 128 - code
            lived = time.monotonic() - began
            deaths, delay = backoff(options, lived, deaths)
            tell(death_text(code, lived, deaths, delay))
            if stop.wait(delay):
                return code if code >= 0 else 128 - code
            life += 1
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def died(code: int, coordinator: bool) -> bool:
    """Whether a robot's process that ended with ``code`` died (killed, a
    crash), as opposed to ending: 0 (its run or its task done), 1 or 2 (it
    could not start or run its part, or was refused: starting it again would
    end the same way) and, for the coordinator, 3 (no configuration left)."""
    return code not in (0, *USER_ERRORS, *((3,) if coordinator else ()))


def again_args(args: Sequence[str], life: int) -> tuple[str, ...]:
    """A robot's command for its ``life``-th start: a ``--trace`` or
    ``--record`` file of its own (``run-pippi.jsonl`` -> ``run-pippi-2.jsonl``:
    the dead process's is kept), and without its ``--inject`` faults (a
    script of one run's faults, by cycle and second: the new process would
    count from 0 and meet them again)."""
    out: list[str] = []
    k = 0
    while k < len(args):
        arg = args[k]
        if arg == "--inject" and k + 1 < len(args):
            k += 2
            continue
        out.append(arg)
        if arg in ("--trace", "--record") and k + 1 < len(args):
            path = Path(args[k + 1])
            out.append(str(path.with_name(f"{path.stem}-{life}{path.suffix}")))
            k += 2
            continue
        k += 1
    return tuple(out)


def status_text(code: int) -> str:
    """A process's exit status as a shell says it: a signal ``N`` is ``128+N``."""
    if code < 0:
        try:
            name = signal.Signals(-code).name
        except ValueError:
            name = f"signal {-code}"
        return f"{128 - code} ({name})"
    return str(code)


def _death_signal() -> Callable[[], None] | None:
    """Linux: what a robot's process calls before its program starts so that it
    gets SIGTERM if the launch dies without stopping it (SIGKILL). Looked up
    here, in the launch: the child, forked while the output pumps run, only
    calls it (importing or loading a library there could deadlock)."""
    if not sys.platform.startswith("linux"):
        return None
    import ctypes

    try:
        prctl = ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None

    def die_with_parent() -> None:  # pragma: no cover - runs in the child, before exec
        prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG

    return die_with_parent


@dataclass
class Started:
    """One robot's running process, its output pump and its last lines."""

    command: RobotCommand
    process: subprocess.Popen[bytes]
    pump: threading.Thread
    tail: deque[str] = field(default_factory=deque)
    reported: bool = False
    began: float = field(default_factory=time.monotonic)
    """When this process was started (monotonic)."""
    life: int = 1
    """Which start of its robot this is (2: the first start again)."""
    deaths: int = 0
    """Deaths of its robot in a row before this start (a process that lasted resets it)."""


class Launch:
    """The processes of a society on this machine (see the module)."""

    def __init__(
        self,
        robots: Sequence[RobotCommand],
        program: Sequence[str] = (sys.executable, "-m", "cfgplan"),
        options: SpawnOptions | None = None,
        out: TextIO | None = None,
    ) -> None:
        self.robots = list(robots)
        self.program = tuple(program)
        self.options = options or SpawnOptions()
        self.out = out or sys.stdout
        self.started: list[Started] = []
        self.stop = threading.Event()
        self._death = _death_signal()
        self._lock = threading.Lock()
        self._closed = False
        self._width = max((len(r.robot) for r in self.robots), default=0)
        self._due: list[tuple[float, Started, int]] = []  # robots to start again: when
        self._print = self._printer()

    # -- output ------------------------------------------------------------------

    def _printer(self) -> Callable[[str, str, str], None]:
        """``print(robot, style, line)``: plain when piped, rich colours on a terminal."""
        colour = self.options.colour
        if colour is None:
            colour = self.out.isatty() and not os.environ.get("NO_COLOR")
        if not colour:

            def plain(robot: str, style: str, line: str) -> None:
                self.out.write(f"{robot.ljust(self._width)} | {line}\n")
                self.out.flush()

            return plain
        from rich.console import Console
        from rich.text import Text

        console = Console(file=self.out, highlight=False, soft_wrap=True)

        def coloured(robot: str, style: str, line: str) -> None:
            text = Text(f"{robot.ljust(self._width)} | ", style=f"bold {style}")
            text.append(line)
            console.print(text)

        return coloured

    def say(self, robot: str, line: str) -> None:
        """One line, prefixed with ``robot`` (a launched robot's colour, or none)."""
        index = next((i for i, r in enumerate(self.robots) if r.robot == robot), None)
        style = "white" if index is None else STYLES[index % len(STYLES)]
        with self._lock:
            if self._closed:
                return
            try:
                self._print(robot, style, line)
            except (BrokenPipeError, ValueError, OSError):  # the reader went (| head): drain on
                self._closed = True

    def _pump(self, robot: str, stream: IO[bytes], tail: deque[str]) -> None:
        for raw in iter(stream.readline, b""):
            line = raw.decode("utf-8", errors="replace").rstrip("\r\n")
            tail.append(line)
            if len(tail) > self.options.tail:
                tail.popleft()
            self.say(robot, line)
        stream.close()

    # -- start -------------------------------------------------------------------

    def start(self) -> None:
        """Start every process in order, each that listens (the router, a
        robot of a mesh) waited for until it does; one that ends first, or
        does not listen in time, is a :class:`RunError` (the caller stops
        the rest). A client of the router is not waited for."""
        for command in self.robots:
            if self.stop.is_set():
                return
            if not command.listens:
                started = self._spawn(command, command.args)
                self.say(command.robot, f"(started: pid {started.process.pid})")
                self.started.append(started)
                continue
            if in_use(command.port, command.host):
                raise RunError(
                    f"port {command.port} on {command.host} is in use: {command.robot} cannot "
                    "listen on it",
                    hint="give another --port, or none (a free port)",
                )
            started = self._spawn(command, command.args)
            self.say(command.robot, f"(started: pid {started.process.pid})")
            self.started.append(started)
            self._listening(started)

    def _spawn(self, command: RobotCommand, args: Sequence[str]) -> Started:
        """Start ``command``'s process with ``args``, its output pumped."""
        process = subprocess.Popen(
            [*self.program, *args],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            env={**os.environ, "PYTHONUNBUFFERED": "1", LAUNCHED: "1"},
            start_new_session=True,  # Ctrl-C reaches the launch, which stops them in order
            preexec_fn=self._death,
        )
        tail: deque[str] = deque()
        assert process.stdout is not None
        pump = threading.Thread(
            target=self._pump,
            args=(command.robot, process.stdout, tail),
            name=f"launch-{command.robot}",
            daemon=True,
        )
        pump.start()
        return Started(command, process, pump, tail)

    def _listening(self, started: Started) -> None:
        """Wait until ``started`` accepts connections on its port (bounded)."""
        command = started.command
        deadline = time.monotonic() + self.options.start_timeout
        while not self.stop.is_set():
            code = started.process.poll()
            if code is not None:
                started.reported = True
                if self.options.respawn and died(code, command.coordinator):
                    self._again(started, code)  # killed or crashed while it started
                    return
                raise self._failed(started, code, "did not start")
            with socket.socket() as probe:
                probe.settimeout(1.0)
                if probe.connect_ex((command.host, command.port)) == 0:
                    return
            if time.monotonic() > deadline:
                raise RunError(
                    f"{command.robot} did not listen on port {command.port} within "
                    f"{self.options.start_timeout:g} s"
                )
            time.sleep(self.options.poll)

    def _failed(self, started: Started, code: int, what: str) -> RunError:
        started.pump.join(timeout=2.0)  # its last lines, whole
        lines = [line.strip() for line in started.tail if line.strip()]
        said = [line for line in lines if "error:" in line] or lines  # not a caret or hint
        last = said[-1].removeprefix("cfgplan: error: ") if said else ""
        return RunError(
            f"{started.command.robot} {what} (exit status {status_text(code)})"
            + (f": {last}" if last else "")
        )

    # -- run ---------------------------------------------------------------------

    def wait(self) -> int:
        """Until the coordinator ends (its status), a robot fails (a
        :class:`RunError`) or :attr:`stop` is set (the coordinator's status
        once stopped)."""
        while not self.stop.is_set():
            for started in list(self.started):
                code = started.process.poll()
                if code is None or started.reported:
                    continue
                started.reported = True
                if self.options.respawn and died(code, started.command.coordinator):
                    self._again(started, code)
                    continue
                if started.command.coordinator:
                    started.pump.join(timeout=2.0)
                    return code if code >= 0 else 128 - code
                if started.command.router:  # every robot is cut off from every other
                    raise self._failed(started, code, "ended: the robots cannot reach each other")
                if code in USER_ERRORS:
                    raise self._failed(started, code, "stopped")
                self.say(started.command.robot, f"(ended, exit status {status_text(code)})")
            self._respawn_due()
            if not self._due and all(s.reported for s in self.started):  # all ended
                return 0
            time.sleep(self.options.poll)
        return -1

    def _again(self, started: Started, code: int) -> None:
        """``started`` died: its robot is started again after a delay that
        doubles with each death in a row (from :attr:`SpawnOptions.respawn_delay`
        to :attr:`SpawnOptions.respawn_most`), a process that ran
        :attr:`SpawnOptions.respawn_reset` seconds or more counting as the
        first death again — as ``ros2 launch``'s ``respawn`` and systemd's
        ``Restart=on-failure`` do."""
        lived = time.monotonic() - started.began
        deaths, delay = backoff(self.options, lived, started.deaths)
        self.say(started.command.robot, death_text(code, lived, deaths, delay))
        self._due.append((time.monotonic() + delay, started, deaths))

    def _respawn_due(self) -> None:
        """Start again the robots whose delay is over (same command: same name,
        port and endpoints; a trace or recording of a file of its own, and no
        scripted faults, which were the first start's: :func:`again_args`)."""
        now = time.monotonic()
        due = [d for d in self._due if d[0] <= now]
        self._due = [d for d in self._due if d[0] > now]
        for _, dead, deaths in due:
            life = dead.life + 1
            dead.pump.join(timeout=2.0)
            started = self._spawn(dead.command, again_args(dead.command.args, life))
            started.life, started.deaths = life, deaths
            self.started[self.started.index(dead)] = started
            self.say(
                dead.command.robot, f"(started again: pid {started.process.pid}, start {life})"
            )

    def stop_all(self) -> int | None:
        """Stop every process still running by its pid, the coordinator first,
        the router last: SIGTERM, at most :attr:`SpawnOptions.stop_wait`
        seconds, then SIGKILL. The coordinator's exit status, if it ran."""
        first = [s for s in self.started if s.command.coordinator]
        rest = [s for s in self.started if not (s.command.coordinator or s.command.router)]
        last = [s for s in self.started if s.command.router]
        for group in (first, rest, last):
            self._signal(group, signal.SIGTERM)
            deadline = time.monotonic() + self.options.stop_wait
            for started in group:
                with contextlib.suppress(subprocess.TimeoutExpired):
                    started.process.wait(max(0.0, deadline - time.monotonic()))
            late = [s for s in group if s.process.poll() is None]
            for started in late:
                self.say(
                    started.command.robot,
                    f"(no end {self.options.stop_wait:g} s after SIGTERM: killed)",
                )
            self._signal(late, signal.SIGKILL)
            for started in late:
                with contextlib.suppress(subprocess.TimeoutExpired):
                    started.process.wait(10.0)
        for started in self.started:
            started.pump.join(timeout=2.0)
        if not first:
            return None
        code = first[0].process.returncode
        return code if code >= 0 else 128 - code

    @staticmethod
    def _signal(group: Sequence[Started], signum: int) -> None:
        for started in group:
            if started.process.poll() is None:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(started.process.pid, signum)

    def run(self) -> int:
        """Start, wait and stop: the exit status (see the module). Ctrl-C or
        SIGTERM stops every robot; a second Ctrl-C kills them at once."""
        previous: dict[int, Any] = {}
        main = threading.current_thread() is threading.main_thread()

        def handler(signum: int, frame: object) -> None:
            if self.stop.is_set() and signum == signal.SIGINT:
                self._signal(self.started, signal.SIGKILL)
            self.stop.set()

        if main:
            for signum in (signal.SIGINT, signal.SIGTERM):
                previous[signum] = signal.signal(signum, handler)
        try:
            status: int | None = None
            try:
                self.start()
                status = self.wait()
            finally:
                stopped = self.stop_all()
            if status == -1:  # stopped: the coordinator's status once stopped
                return stopped if stopped is not None else 0
            return status or 0
        finally:
            for s, h in previous.items():
                signal.signal(s, h)
