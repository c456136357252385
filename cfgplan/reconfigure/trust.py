"""What a helper may say to the coordinator in its own name (5.5; the threat
model of a secured society, docs/how-to/secure-a-society.md): the rule the
coordinator applies to every report (:mod:`cfgplan.reconfigure.network`),
whoever holds the helper's key."""

from __future__ import annotations

from cfgplan.runtime.errors import printable
from cfgplan.runtime.faults import term_text
from cfgplan.runtime.monitor import Detection

__all__ = ["beyond_its_own"]


def beyond_its_own(detection: Detection) -> str | None:
    """What ``detection``, reported by ``detection.robot``, says beyond that
    robot's own business, or ``None``: a helper may report the failure,
    recovery or accomplished task of a functionality instance that runs on
    it (an instance's first argument is its robot, 3.2), and what it sees of
    its own inputs (stale, fresh); a state update is the coordinator's
    operator's alone (a helper's ``--inject assert``/``retract`` is not
    applied where it runs). With ``--keys`` a report comes from the robot it
    names, so this is what a compromised robot could otherwise say of others
    (remove ``(camera Emil)``, fail ``compass(Emil)``, stop the society)."""
    if detection.kind == "facts":
        return "a state update (only the coordinator's operator updates the state)"
    if detection.kind in ("failure", "recovery", "achieved"):
        instance = detection.instance
        if len(instance) < 2 or instance[1] != detection.robot:
            shown = printable(term_text(instance)[:80]) if instance else "no instance"
            what = {"failure": "the failure", "recovery": "the recovery"}.get(
                detection.kind, "the task accomplished"
            )
            return f"{what} of {shown}, which does not run on it"
    return None
