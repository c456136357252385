"""Which problem a robot runs: its fingerprint, so that two societies under one name refuse
each other instead of mixing their values.

A society's name (``--society``, ``default`` unless given) is all that keeps
two societies on one network apart (:mod:`cfgplan.runtime.keys`); two teams
that both leave it out would exchange values, switches and losses. So a
robot that knows its problem announces it, beside its liveliness token, as a
second token ``cfgplan/<society>/<robot>/problem/<fingerprint>/<about>``
(:func:`cfgplan.runtime.keys.problem_key`), and watches the others'. A robot
of the same society that announces another fingerprint runs another problem.
The one out of place stops, alone: a robot that has met no robot of its own
problem (another robot announcing its fingerprint) once the other's token has
been up for a lease says so, naming both problems, and stops with exit
status 1 (:attr:`cfgplan.runtime.zenoh_transport.ZenohTransport.conflict`): a
robot restarted with an edited state, a second team's robot under the same
society name. A robot that has met one of its own is a member of a society
that runs its problem: it says once that the other is not of its society and
goes on — a token alone (anyone's, without keys; a member's own, with them)
never stops a society. Robots of one problem announce one fingerprint and
join as before.

The **fingerprint** is the first 16 hex digits of the SHA-256 of the
problem's canonical text: the domain and the state as the printer writes
them back (:mod:`cfgplan.syntax.printer`: no comments, no layout, numbers in
one form), the state without its goals, then the goals planned for, one a
line (``--goal`` counts, the state's ``goal`` or ``sequence`` otherwise). So
reformatting or commenting a file changes nothing; reordering facts,
functionalities or methods does (their order decides the planner's ties,
6.3.2), and so does another goal. Ranks, weights and options are not part of
it: they choose among the configurations of one problem.

``about`` says which problem it is to a person: the domain's and the state's
file names and the goal, at most :data:`MAX_ABOUT` characters.

``cfgplan run --robot`` knows its problem; a program ``cfgplan emit --lang
python`` wrote carries its problem's fingerprint (``PROBLEM``, passed to
:func:`cfgplan.runtime.robot_main`). A robot program that does not know its
problem (written by hand, without ``problem=``) announces nothing and checks
nothing; the robots of its society that know theirs do. Read from the
network, a token is bounded: a fingerprint is 16 hex digits, ``about`` at
most :data:`MAX_ABOUT` characters once decoded, printed with control
characters escaped; anything else is ignored.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from cfgplan.notation import call_text

if TYPE_CHECKING:
    from cfgplan.problem import Problem

__all__ = ["MAX_ABOUT", "ProblemId", "conflict_message", "problem_id", "stranger_message"]

MAX_ABOUT = 160
"""The most characters of a problem's description that are announced and read."""
FINGERPRINT = re.compile(r"^[0-9a-f]{16}$")


@dataclass(frozen=True)
class ProblemId:
    """A problem as robots announce it: ``fingerprint`` (16 hex digits) and ``about``."""

    fingerprint: str
    about: str

    def __post_init__(self) -> None:
        if not FINGERPRINT.match(self.fingerprint):
            raise ValueError(f"{self.fingerprint!r} is not a problem's fingerprint")
        object.__setattr__(self, "about", clip_about(self.about))

    def __str__(self) -> str:
        return f"{self.about} [{self.fingerprint}]"


def clip_about(text: str) -> str:
    """``text`` printable and at most :data:`MAX_ABOUT` characters."""
    # Here, not at the top: the runtime imports this module as it starts, and
    # this module may be imported first (cfgplan emit).
    from cfgplan.run_errors import printable

    text = printable(text)
    return text if len(text) <= MAX_ABOUT else text[: MAX_ABOUT - 1] + "…"


def canonical_text(problem: Problem) -> str:
    """The text the fingerprint is the hash of (module docstring)."""
    from cfgplan.syntax.printer import print_domain, print_state

    state = problem.state.model_copy(update={"goal": None, "sequence": ()})
    goals = "\n".join(call_text((g.call.predicate, *map(str, g.call.args))) for g in problem.goals)
    return f"{print_domain(problem.domain)}\f\n{print_state(state)}\f\n{goals}\n"


def problem_id(problem: Problem, domain: Path | str, state: Path | str) -> ProblemId:
    """The fingerprint and description of ``problem``, read from ``domain`` and ``state``."""
    digest = hashlib.sha256(canonical_text(problem).encode()).hexdigest()[:16]
    calls = [call_text((g.call.predicate, *map(str, g.call.args))) for g in problem.goals]
    goal = calls[0] + (f" (then {len(calls) - 1} more)" if len(calls) > 1 else "")
    about = f"{Path(domain).name} with {Path(state).name}, goal {goal}"
    return ProblemId(digest, about)


def conflict_message(society: str, mine: ProblemId, robot: str, theirs: ProblemId) -> str:
    """What a robot says when ``robot`` of its society runs another problem and
    it met no robot of its own: it is the one out of place, and stops."""
    return (
        f"society {society} runs two problems: this robot runs {mine}, robot {robot} "
        f"runs {theirs}; this one, which met no robot of its own problem, stops. Start it "
        "with the society's domain, state and goals, or give each problem its own "
        "society: --society NAME"
    )


def stranger_message(society: str, mine: ProblemId, robot: str, theirs: ProblemId) -> str:
    """What a robot of a society says when ``robot`` announces another problem:
    it is not of this society, and is not acted on."""
    return (
        f"robot {robot} announces another problem than society {society}'s: it runs "
        f"{theirs}, this society {mine}; not of this society, ignored (a robot started "
        "with another problem stops by itself)"
    )
