"""A robot's side of switching configurations across processes (5.5): the protocol's member.

The robot that owns the goal (the coordinator, which plans) switches the
society in two phases, so that every robot switches to the same
configuration and nobody runs half of two:

1. **prepare** ``{"op": "prepare", "id": N, "from": C, "part": ...}`` to each
   robot of the new configuration (:func:`~cfgplan.runtime.part.part_to_json`;
   an empty part for a robot that leaves it). The robot checks that it can run
   its part (every implementation is there) and answers ``ready`` or
   ``refused`` with the reason; it keeps running the old configuration.
2. **commit** ``{"op": "commit", "id": N}`` once every robot is ready: each
   installs its part between two of its cycles
   (:func:`~cfgplan.runtime.install.install`, keeping what both
   configurations share) and answers ``installed``. A robot that refused or
   did not answer in time makes the coordinator send **abort** instead, and
   plan again without it.

Answers go to the coordinator's key as ``{"type": "ack", "robot": R, "id":
N, "phase": "ready" | "refused" | "installed", "reason": ...}``; a robot's
detections go there too as ``{"type": "report", "robot": R, "detection":
...}``, each stamped with the id of the configuration it ran (its
``config``: a report is placed by that, not by the robots' clocks). A
commit may carry the part itself (``"part"``): the coordinator so
re-synchronises a robot that appears (started late, or back after a crash).
``{"op": "finish", "goal": G}`` ends the run when the action's task is
accomplished: the robot records a ``finish`` event (the console says the task
is accomplished), answers ``finished``, and ends its run; the coordinator
leaves once every robot has answered (or after a time limit), so that no robot
takes the others' leaving for a loss (:meth:`~cfgplan.runtime.Robot.release`).
Messages are idempotent: a repeated prepare or commit is answered again,
an old id is ignored. Every message carries the coordinator's ``epoch``,
drawn when it starts: a coordinator started again numbers its
configurations afresh, and a robot that hears a new epoch on a prepare or
commit follows it from its first id. Messages come from other processes:
what cannot be read is recorded as an error and ignored.

Channels the two configurations share carry the same data either side of a
commit (the same instances at both ends, :mod:`~cfgplan.reconfigure.switch`),
so a robot that has switched and one that has not yet still understand each
other; channels of only the new configuration carry data once both ends have
switched.
"""

from __future__ import annotations

import json
import time
from dataclasses import replace
from typing import Any, Protocol

from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import Adaptation, Lifecycle
from cfgplan.runtime.executor import Robot
from cfgplan.runtime.install import install, runnable
from cfgplan.runtime.keys import configure_key, coordinator_key
from cfgplan.runtime.monitor import Monitor
from cfgplan.runtime.part import Part, part_from_json
from cfgplan.runtime.wire import whole

__all__ = ["Member", "Membership", "Network", "send"]


class Network(Protocol):
    """What the protocol needs of a transport (the Zenoh one has it)."""

    society: str

    def subscribe(self, key: str, handler: Any) -> None: ...

    def publish(self, key: str, payload: bytes) -> None: ...


def send(network: Network, key: str, message: dict[str, object]) -> None:
    network.publish(key, json.dumps(message, separators=(",", ":")).encode())


class Member:
    """Answers the coordinator for ``robot`` and forwards its detections."""

    def __init__(
        self,
        robot: Robot,
        network: Network,
        monitor: Monitor | None = None,
        *,
        forward: bool = True,
    ) -> None:
        self.robot = robot
        self.network = network
        self.monitor = monitor
        self.forward = forward  # False on the coordinator: it reads its monitor itself
        self.current = 0  # the configuration id it runs
        self.epoch = ""  # the coordinator's run it follows (``epoch`` of its messages)
        self.pending: dict[int, Part] = {}
        self.finished: str | None = None
        network.subscribe(configure_key(network.society, robot.name), self.receive)
        declare = getattr(network, "declare", None)
        if declare is not None:  # the first answer then goes out at once
            declare(coordinator_key(network.society))

    def receive(self, payload: bytes) -> None:
        """One message from the coordinator (on the robot's thread, between cycles)."""
        try:
            message = json.loads(payload)
            op, number = message["op"], whole(message["id"], "a configuration id")
            epoch = message.get("epoch", "")
            if not isinstance(op, str) or not isinstance(epoch, str):
                raise ValueError("op and epoch are strings")
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            self._error(f"a switch message that cannot be read: {exc}")
            return
        if epoch != self.epoch and op in ("prepare", "commit"):
            # A coordinator started again (or another one): it numbers its
            # configurations afresh, and this robot keeps running its part
            # until that coordinator installs one.
            self.epoch, self.current, self.pending = epoch, 0, {}
        elif epoch != self.epoch and op == "abort":
            return  # of a switch of a coordinator no longer followed
        if op == "prepare":
            self._prepare(number, message.get("part"))
        elif op == "commit":
            self._commit(number, message.get("part"))
        elif op == "abort":
            self.pending.pop(number, None)
        elif op == "finish":
            self._finish(number, message, epoch)

    def _finish(self, number: int, message: dict[str, object], epoch: str) -> None:
        """The coordinator says the task is accomplished: say so, answer, end the run."""
        if self.finished is None:
            self.finished = "achieved"
            self.robot.release()
            info: list[tuple[str, object]] = [("id", number)]
            for name in ("from", "goal"):
                value = message.get(name)
                if isinstance(value, str) and value:
                    info.append((name, value))
            self.robot.record(
                Adaptation(robot=self.robot.name, t=time.time(), what="finish", info=tuple(info))
            )
        self._ack(number, "finished", epoch=epoch)  # whoever said it

    def refusal(self, part: Part) -> str | None:
        """Why this robot cannot run ``part`` (:func:`~cfgplan.runtime.install.runnable`),
        or None: the check a prepare makes, for the coordinator's own part."""
        try:
            runnable(self.robot, part)
        except (ValueError, RunError) as exc:
            return str(exc)
        return None

    def _part(self, data: object) -> Part:
        part = part_from_json(data)
        runnable(self.robot, part)
        return part

    def _prepare(self, number: int, data: object) -> None:
        if number in self.pending:  # a repeated prepare
            self._ack(number, "ready")
            return
        if number <= self.current:
            return  # a switch older than the configuration it runs: ignored
        try:
            part = self._part(data)
        except (ValueError, RunError) as exc:
            self._ack(number, "refused", str(exc))
            return
        self.pending[number] = part
        self._ack(number, "ready")

    def _commit(self, number: int, data: object) -> None:
        if number == self.current and data is None:
            self._ack(number, "installed")  # a repeated commit
            return
        if number < self.current:
            return
        try:
            part = self.pending.pop(number) if data is None else self._part(data)
        except KeyError:
            self._ack(number, "refused", f"configuration {number} was never prepared here")
            return
        except (ValueError, RunError) as exc:
            self._ack(number, "refused", str(exc))
            return
        self.install(number, part)
        self._ack(number, "installed")

    def install(self, number: int, part: Part) -> None:
        """Run ``part`` as configuration ``number`` from the next cycle on."""
        installed = install(self.robot, part)
        same = number == self.current and not installed.changed  # a re-synchronisation
        self.current = number
        self.pending = {k: v for k, v in self.pending.items() if k > number}
        if same:
            return
        self.robot.record(
            Adaptation(
                robot=self.robot.name,
                t=time.time(),
                what="install",
                info=(("id", number), *installed.record()),
            )
        )

    def _ack(self, number: int, phase: str, reason: str = "", epoch: str | None = None) -> None:
        message: dict[str, object] = {
            "type": "ack",
            "robot": self.robot.name,
            "id": number,
            "phase": phase,
            "epoch": self.epoch if epoch is None else epoch,
        }
        if reason:
            message["reason"] = reason
        send(self.network, coordinator_key(self.network.society), message)

    def report(self) -> None:
        """Send the detections of this robot's monitor to the coordinator."""
        if self.monitor is None or not self.forward:
            return
        for detection in self.monitor.drain():
            made_under = replace(detection, config=self.current)  # the cycle just run's
            message = {
                "type": "report",
                "robot": self.robot.name,
                "detection": json.loads(made_under.message()),
            }
            send(self.network, coordinator_key(self.network.society), message)

    def _error(self, message: str) -> None:
        self.robot.record(
            Lifecycle(
                robot=self.robot.name, t=time.time(), what="error", info=(("message", message),)
            )
        )


class Membership:
    """The hooks of :func:`cfgplan.runtime.execute` for a robot that follows a
    coordinator: scripted faults before each cycle, detections sent after."""

    def __init__(self, member: Member, before: Any = None) -> None:
        self.member = member
        self._before = before
        self.stopped = False
        self.reconfigures = True

    def before(self, cycle: int, elapsed: float) -> None:
        if self._before is not None:
            self._before(cycle, elapsed)

    def between(self, cycle: int, elapsed: float) -> None:
        self.member.report()

    def close(self) -> None:
        """Nothing runs beside the loop."""

    @property
    def finished(self) -> str | None:
        return self.member.finished
