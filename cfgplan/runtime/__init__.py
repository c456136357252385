"""Running configurations (thesis chapter 5, 5.2).

The basic components of 5.2: the :class:`Channel` (one slot, newer data
overwrites, last operation read or write; local or global behind one
interface), the :class:`Wrapper` that runs a functionality's actual function
only on fresh input, the :class:`Registry` of actual functions users declare
with :func:`functionality`, a :class:`Transport` for global channels, and the
:class:`Robot` / :class:`Society` that run individual configurations cycle by
cycle. Code written by ``cfgplan emit --lang python`` uses these.
"""

from cfgplan.runtime.channel import Channel, make_global_channel, make_local_channel
from cfgplan.runtime.executor import (
    Configure,
    Cycle,
    Robot,
    Society,
    assemble,
    build,
    robot_main,
    society,
    society_main,
)
from cfgplan.runtime.registry import (
    Implementation,
    Registry,
    functionality,
    load_module,
)
from cfgplan.runtime.trace import describe, show, summary
from cfgplan.runtime.transport import InProcessTransport, Transport
from cfgplan.runtime.wrapper import Event, Wrapper, current_robot

__all__ = [
    "Channel",
    "Configure",
    "Cycle",
    "Event",
    "Implementation",
    "InProcessTransport",
    "Registry",
    "Robot",
    "Society",
    "Transport",
    "Wrapper",
    "assemble",
    "build",
    "current_robot",
    "describe",
    "functionality",
    "load_module",
    "make_global_channel",
    "make_local_channel",
    "robot_main",
    "show",
    "society",
    "society_main",
    "summary",
]
