"""Blame what failed (5.5): a stale link is waited for, a silent
computation is not.

Robot X runs ``a(X)`` and ``b(X)``, each sending to ``c(Y)`` on robot Y over
a global channel. Both inputs of ``c`` stale at once say nothing about ``a``
or ``b``: X or the link between them fell silent (a lost packet is resent
after 200 ms or more), and the suspicion waits the grace, during which X's
lease decides. One stale while the other flows is evidence about its sender:
it is acted on at its staleness limit. The clock is stepped by hand.
"""

from __future__ import annotations

from types import SimpleNamespace

from cfgplan.configuration.model import Channel, Configuration, FunctionalityInstance
from cfgplan.planner import plan
from cfgplan.problem import load
from cfgplan.reconfigure.suspect import SILENT_LINK, Blamed, Suspicions
from cfgplan.runtime.monitor import Detection
from tests.reconfigure.test_coordinate import STEP2, Clock

LINK = Configuration(
    functionalities=(
        FunctionalityInstance(label="F1", name="a", args=("X",)),
        FunctionalityInstance(label="F2", name="b", args=("X",)),
        FunctionalityInstance(label="F3", name="c", args=("Y",)),
    ),
    channels=tuple(
        Channel(kind="global", source=s, target="F3", source_robot="X", target_robot="Y", data=(d,))
        for s, d in (("F1", "p"), ("F2", "q"))
    ),
    cost=25,
)


def _stale(label: str, kind: str = "stale") -> Detection:
    return Detection(kind, "Y", 1.0, label=label, other="X", detail=f"{label}->F3", limit=0.3)  # type: ignore[arg-type]


def test_a_computation_whose_outputs_stop_while_its_robots_others_flow_is_blamed_at_the_limit() -> (
    None
):
    clock = Clock()
    suspicions = Suspicions(clock, grace=2.0)
    suspicions.note(_stale("F1"))
    clock.now += 0.29
    assert suspicions.settled(LINK) is None
    clock.now += 0.02
    blamed = suspicions.settled(LINK)
    assert blamed is not None and blamed.label == "F1" and blamed.how == "stale"


def test_a_link_whose_every_channel_is_stale_is_waited_for_the_grace() -> None:
    clock = Clock()
    suspicions = Suspicions(clock, grace=2.0)
    suspicions.note(_stale("F1"))
    suspicions.note(_stale("F2"))
    clock.now += 1.9
    assert suspicions.settled(LINK) is None  # a stalled link: not a failure yet
    suspicions.note(_stale("F2", "fresh"))  # data again from b(X): a(X) alone is silent
    blamed = suspicions.settled(LINK)
    assert blamed is not None and blamed.label == "F1"


def test_a_link_silent_past_the_grace_blames_its_first_sender_as_a_silent_link() -> None:
    clock = Clock()
    suspicions = Suspicions(clock, grace=2.0)
    suspicions.note(_stale("F1"))
    suspicions.note(_stale("F2"))
    clock.now += 2.01
    blamed = suspicions.settled(LINK)
    assert blamed is not None and blamed.label == "F1" and blamed.how == SILENT_LINK
    assert blamed.detail == "input F1->F3 stale for over 2 s"


def test_a_silent_links_blame_is_tried_again_after_the_plain_hold_each_time() -> None:
    """A computation blamed on evidence waits a hold doubled with each blame;
    one blamed only because its link fell silent waits the plain hold each
    time: once the link is back, its society serves again within hold + 1 s."""
    situation = SimpleNamespace(failed={("a", "X")}, lost=())
    blamed = Blamed(1.0)
    for n in range(4):
        blamed.blame(("a", "X"), "X", 10.0 * n, doubling=False)
        assert blamed.due(situation, 10.0 * n + 0.99) == []  # type: ignore[arg-type]
        assert blamed.due(situation, 10.0 * n + 1.0) == [("a", "X")]  # type: ignore[arg-type]
        blamed.forget(("a", "X"))
    blamed.blame(("a", "X"), "X", 100.0)  # on evidence: the fifth blame's hold
    assert blamed.due(situation, 100.0 + 15.9) == []  # type: ignore[arg-type]


def test_without_grace_a_silent_link_is_blamed_at_the_limit() -> None:
    """Robots of one process share no link: the thesis's rule, at once."""
    clock = Clock()
    suspicions = Suspicions(clock)
    suspicions.note(_stale("F1"))
    suspicions.note(_stale("F2"))
    clock.now += 0.31
    assert suspicions.settled(LINK) is not None


def test_a_starved_functionality_is_not_blamed_between_its_feeders_fresh_and_its_own() -> None:
    """From the fault benchmark at 10 % loss: Emil's compass (F10) went stale
    on Pippi, so her measure-robot-orient-compass (F12) starved and its output
    went stale too. The compass's data came back; Pippi said so in one
    message and that F12 was fed again in the next, and between the two the
    coordinator blamed F12 (a spurious switch). A starved suspicion's clock
    now starts only when nothing upstream of it is suspected any more."""
    problem = load(*STEP2)
    (config, *_), _ = plan(problem.task, problem.goal_call)
    clock = Clock()
    suspicions = Suspicions(clock, grace=2.0)

    def on_pippi(label: str, sender: str, kind: str = "stale") -> Detection:
        return Detection(kind, "Pippi", 1.0, label=label, other=sender, detail=label, limit=0.15)  # type: ignore[arg-type]

    suspicions.note(on_pippi("F10", "Emil"))  # global-orient from Emil's compass
    suspicions.note(on_pippi("F12", "Pippi"))  # F12 -> F7, starved
    clock.now += 0.5
    assert suspicions.settled(config) is None
    suspicions.note(on_pippi("F10", "Emil", "fresh"))  # the compass's data is back
    clock.now += 0.01
    assert suspicions.settled(config) is None  # F12's own fresh is on its way
    clock.now += 0.1
    assert suspicions.settled(config) is None
    suspicions.note(on_pippi("F12", "Pippi", "fresh"))
    clock.now += 1.0
    assert suspicions.settled(config) is None


def test_a_functionality_fed_again_that_stays_silent_is_blamed_at_its_limit() -> None:
    problem = load(*STEP2)
    (config, *_), _ = plan(problem.task, problem.goal_call)
    clock = Clock()
    suspicions = Suspicions(clock, grace=2.0)
    for label, sender in (("F10", "Emil"), ("F12", "Pippi")):
        suspicions.note(
            Detection("stale", "Pippi", 1.0, label=label, other=sender, detail=label, limit=0.15)
        )
    clock.now += 0.5
    assert suspicions.settled(config) is None
    suspicions.note(Detection("fresh", "Pippi", 1.0, label="F10", other="Emil", detail="F10"))
    assert suspicions.settled(config) is None
    clock.now += 0.16
    blamed = suspicions.settled(config)
    assert blamed is not None and blamed.label == "F12" and blamed.how == "stale"


def test_what_another_robot_reported_stale_is_waited_for_as_its_reports_travel() -> None:
    """From the fault benchmark with 100 ms delay and 5 % loss: Pippi's fresh
    report of a starved functionality's output came more than its 0.15 s
    limit after the one that fed it (a lost packet is resent after 200 ms or
    more), and the coordinator switched. What another robot saw now waits
    ``reported`` seconds at least; what the coordinator saw itself does not."""
    clock = Clock()
    suspicions = Suspicions(clock, grace=2.0, here="Y", reported=1.0)
    suspicions.note(_stale("F1"))  # seen on Y: the coordinator's robot
    clock.now += 0.31
    assert suspicions.settled(LINK) is not None
    elsewhere = Suspicions(clock, grace=2.0, here="Z", reported=1.0)
    elsewhere.note(_stale("F1"))  # seen on Y, reported to Z
    clock.now += 0.31
    assert elsewhere.settled(LINK) is None
    clock.now += 0.7
    blamed = elsewhere.settled(LINK)
    assert blamed is not None and blamed.detail == "input F1->F3 stale for over 1 s"


def test_what_went_stale_because_a_robot_stood_still_is_excused_until_its_deadline() -> None:
    """Found in CI: the coordinator X frozen 4 s came back, Y's report that
    X's outputs stopped arrived before the fresh data (the machine was
    loaded), and X's own computation was recorded as failed. Excused, a
    suspicion X is part of does not ripen before the deadline; its clock
    starts again then, so what really stopped is still blamed, one limit
    later. A suspicion between two other robots is not excused."""
    clock = Clock()
    suspicions = Suspicions(clock)
    suspicions.note(_stale("F1"))  # X's a(X), seen stale by Y
    suspicions.excuse("X", until=clock.now + 2.0)
    clock.now += 1.99
    assert suspicions.settled(LINK) is None
    clock.now += 0.02  # the excuse is over: the limit is counted from here
    assert suspicions.settled(LINK) is None
    clock.now += 0.29
    assert suspicions.settled(LINK) is None
    clock.now += 0.02
    blamed = suspicions.settled(LINK)
    assert blamed is not None and blamed.label == "F1"
    suspicions.note(_stale("F2"))
    suspicions.excuse("Z", until=clock.now + 2.0)  # another robot stood still
    clock.now += 0.31
    blamed = suspicions.settled(LINK)
    assert blamed is not None and blamed.label == "F2"


def test_an_excused_suspicion_withdrawn_by_fresh_data_is_never_blamed() -> None:
    clock = Clock()
    suspicions = Suspicions(clock)
    suspicions.note(_stale("F1"))
    suspicions.excuse("Y", until=clock.now + 2.0)  # the robot that saw it stood still
    clock.now += 1.5
    assert suspicions.settled(LINK) is None
    suspicions.note(_stale("F1", "fresh"))
    clock.now += 5.0
    assert suspicions.settled(LINK) is None
