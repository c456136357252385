"""Running configurations (thesis chapter 5, 5.2).

The basic components of 5.2: the :class:`Channel` (one slot, newer data
overwrites, last operation read or write; local or global behind one
interface), the :class:`Wrapper` that runs a functionality's actual function
only on fresh input, the :class:`Registry` of actual functions users declare
with :func:`functionality`, a :class:`Transport` for global channels (in
process, or :class:`~cfgplan.runtime.zenoh_transport.ZenohTransport` across
processes and hosts), and the :class:`Robot` / :class:`Society` that run
individual configurations cycle by cycle. Code written by ``cfgplan emit
--lang python`` uses these.

For monitoring and reconfiguration (5.5): implementations raise
:class:`ResourceFailure` when their resource fails (and actions return
:data:`ACHIEVED` when their task is done); :func:`install` puts a new part
on a running robot with the least disruption; the
:class:`~cfgplan.runtime.monitor.Monitor` turns events into detections.

Importing this package is light: no planner, IR, pydantic, lark or Zenoh (a
robot runs its emitted program with only this); Zenoh is imported when a
Zenoh transport is opened.
"""

from cfgplan.runtime.channel import Channel, make_global_channel, make_local_channel
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.events import (
    Adaptation,
    Call,
    Event,
    Lifecycle,
    Presence,
    Staleness,
    Transfer,
)
from cfgplan.runtime.executor import Configure, Cycle, Listener, Robot
from cfgplan.runtime.faults import ACHIEVED, ResourceFailure
from cfgplan.runtime.install import Installed, build, install
from cfgplan.runtime.launch import RunOptions, execute
from cfgplan.runtime.main import robot_main, society_main
from cfgplan.runtime.part import CallSpec, ChannelSpec, Part
from cfgplan.runtime.registry import (
    Implementation,
    Registry,
    functionality,
    load_module,
)
from cfgplan.runtime.society import Society, assemble, society
from cfgplan.runtime.trace import describe, show, summary
from cfgplan.runtime.transport import ChannelKey, InProcessTransport, Transport
from cfgplan.runtime.wrapper import Wrapper, current_robot

__all__ = [
    "ACHIEVED",
    "Adaptation",
    "Call",
    "CallSpec",
    "Channel",
    "ChannelKey",
    "ChannelSpec",
    "Configure",
    "Cycle",
    "Event",
    "Implementation",
    "InProcessTransport",
    "Installed",
    "Lifecycle",
    "Listener",
    "Part",
    "Presence",
    "Registry",
    "ResourceFailure",
    "Robot",
    "RunError",
    "RunOptions",
    "Society",
    "Staleness",
    "Transfer",
    "Transport",
    "Wrapper",
    "assemble",
    "build",
    "current_robot",
    "describe",
    "execute",
    "functionality",
    "install",
    "load_module",
    "make_global_channel",
    "make_local_channel",
    "robot_main",
    "show",
    "society",
    "society_main",
    "summary",
]
