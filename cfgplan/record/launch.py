"""``--record FILE.mcap`` and ``--foxglove [HOST:]PORT`` beside a run.

The command line calls these; each imports its package (``mcap``, or
``foxglove-sdk``) only when its option is given, and says which extra to
install when it is missing (a :class:`RunError`, exit status 1, no
traceback). A robot without these options never imports either.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from cfgplan.configuration.model import Configuration
from cfgplan.live.address import Address
from cfgplan.record.policy import FOXGLOVE_HINT, RECORD_HINT, Policy
from cfgplan.runtime.errors import RunError
from cfgplan.runtime.launch import Hooks
from cfgplan.runtime.society import Society

if TYPE_CHECKING:
    from cfgplan.record.foxglove_live import FoxgloveLive
    from cfgplan.record.live import LiveRecorder

__all__ = ["open_foxglove", "start_recording"]

_RECORD_NEEDS = ("mcap", "zstandard", "lz4")


def start_recording(path: Path, force: bool, policy: Policy | None = None) -> LiveRecorder:
    """A new recording at ``path`` (:func:`cfgplan.record.live.open_recording`);
    a :class:`RunError` naming the extra when ``mcap`` is missing."""
    try:
        from cfgplan.record.live import open_recording
    except ModuleNotFoundError as exc:
        package = (exc.name or "").split(".")[0]
        if package not in _RECORD_NEEDS:
            raise
        raise RunError(
            f"--record needs the {package} package, which is not installed", hint=RECORD_HINT
        ) from None
    return open_recording(path, force, policy)


def open_foxglove(
    address: Address,
    society: Society,
    hooks: Hooks | None,
    config: Configuration,
    goal: tuple[str, ...],
    title: str,
) -> FoxgloveLive:
    """Serve the run to Foxglove at ``address``; print its ``ws://`` URL. The
    graph follows the coordinator's running configuration while this process
    runs the coordinator (``hooks``: from the start, or once its robot took
    over), else stays the last one it showed (``config`` at first). The
    society's topics are published by the coordinator: the robot of ``goal``
    (the goal's ground call), then whoever takes over."""
    try:
        import foxglove  # noqa: F401  (the foxglove extra)
    except ImportError:
        raise RunError(
            "--foxglove needs the foxglove-sdk package, which is not installed",
            hint=FOXGLOVE_HINT,
        ) from None
    from cfgplan.reconfigure.owner import coordinator_of
    from cfgplan.reconfigure.succession import Shown, coordinating
    from cfgplan.record.foxglove_live import serve

    coordinator = coordinating(hooks)
    running = Shown(hooks, config).running  # a robot that takes over: its configurations
    here = [r.name for r in society.robots]
    lead = coordinator.robot if coordinator is not None else coordinator_of(goal, config)
    try:
        live = serve(address, title, config, here, lead, running)
    except Exception as exc:  # the SDK raises its own error types for a port in use
        where = f"[{address.host}]" if ":" in address.host else address.host
        raise RunError(
            f"cannot serve Foxglove on {where}:{address.port}: {exc}",
            hint="give another port, or 0 for any free one",
        ) from None
    host = address.host
    if host in ("0.0.0.0", "::"):
        host = "127.0.0.1" if host == "0.0.0.0" else "::1"
    shown = f"[{host}]" if ":" in host else host
    print(f"foxglove: ws://{shown}:{live.port}", flush=True)
    return live
