"""The live page's model (cfgplan.live.model): a pure function of a run's events."""

from __future__ import annotations

from cfgplan.live.model import Limits, Setup, input_key, model
from cfgplan.runtime.events import Adaptation, Call, Lifecycle, Presence, Staleness, Transfer
from cfgplan.runtime.transport import ChannelKey

SETUP = Setup(
    title="cross-door", robots=("Emil", "Pippi"), here=("Emil", "Pippi"), coordinator="Emil"
)
POS = ("pos", "Emil", "Door1")
KEY = ChannelKey("F7", "F3", POS)


def _call(status: str, **more: object) -> Call:
    return Call(
        robot="Emil", cycle=3, t=3.0, label="F3", name="cross-door", args=("Emil",),
        status=status, **more,  # type: ignore[arg-type]
    )  # fmt: skip


def _stale(state: str, t: float) -> Staleness:
    return Staleness(
        robot="Emil", t=t, state=state, label="F3", channel=KEY,  # type: ignore[arg-type]
        source_robot="Pippi", age=1.0, period=0.1, limit=0.3,
    )  # fmt: skip


def _switch(t: float = 5.0) -> Adaptation:
    info = {
        "id": 1,
        "cause": "compass(Emil) failed",
        "from_cost": 44,
        "to_cost": 47,
        "source": "fallback",
        "stopped": {"functionalities": ["F10: compass(Emil)"]},
        "started": {"functionalities": ["F17: camera(Emil)"]},
    }
    return Adaptation(robot="Emil", cycle=40, t=t, what="switch", info=tuple(info.items()))


def _failure(resource: str = "compass(Emil)", kind: str = "functionality") -> Adaptation:
    info = {"detected_by": "Emil", "resource": resource, "kind": kind, "how": "injected"}
    return Adaptation(robot="Emil", cycle=40, t=4.9, what="failure", info=tuple(info.items()))


def test_the_first_page_knows_its_robots_but_not_their_state() -> None:
    """Before any event: every robot unknown, nothing failed, no timeline."""
    page = model([], SETUP)
    assert page["robots"] == {
        "Emil": {"state": "unknown", "cycle": None, "t": None},
        "Pippi": {"state": "unknown", "cycle": None, "t": None},
    }
    assert page["failed"] == {} and page["timeline"] == [] and page["switches"] == 0
    assert page["decides"] is True


def test_an_input_is_waiting_then_fresh_then_stale_then_fresh_again() -> None:
    """Calls and staleness events set the state of the input they concern."""
    key = input_key("F3", POS)
    assert key == "F3 pos(Emil, Door1)"
    assert model([_call("waiting", waiting=(POS,))], SETUP)["inputs"][key]["state"] == "waiting"
    ran = _call("ran", inputs=((POS, [1.0, 2.0]),))
    assert model([ran], SETUP)["inputs"][key] == {"state": "fresh", "t": 3.0}
    assert model([ran, _stale("stale", 4.0)], SETUP)["inputs"][key]["state"] == "stale"
    back = model([ran, _stale("stale", 4.0), _stale("fresh", 4.5)], SETUP)["inputs"][key]
    assert back == {"state": "fresh", "t": 4.5}
    refused = model([ran, _call("stale", stale=(POS,))], SETUP)["inputs"][key]
    assert refused == {"state": "stale", "t": 3.0}  # the last data is still that of cycle 3


def test_a_message_moves_the_time_of_an_input_on() -> None:
    """A transfer on a channel refreshes its input's time, not its state."""
    message = Transfer(
        robot="Emil", t=6.0, direction="receive", channel=KEY, other="Pippi", value=1, seq=9
    )
    inputs = model([_stale("stale", 4.0), message], SETUP)["inputs"]
    assert inputs[input_key("F3", POS)] == {"state": "stale", "t": 6.0}


def test_robots_are_running_lost_and_stopped_as_the_events_say() -> None:
    """A robot's own event makes it running; another's loss or a robot failure
    makes it lost; its stop makes it stopped."""
    seen = Presence(robot="Emil", cycle=1, t=1.0, other="Pippi", alive=True)
    lost = Presence(robot="Emil", cycle=2, t=2.0, other="Pippi", alive=False)
    stop = Lifecycle(robot="Emil", cycle=9, t=9.0, what="stop", info=(("why", "cycles"),))
    page = model([seen], SETUP)
    assert page["robots"]["Emil"]["state"] == "running"
    assert page["robots"]["Emil"]["cycle"] == 1
    assert page["robots"]["Pippi"]["state"] == "running"
    assert model([seen, lost], SETUP)["robots"]["Pippi"]["state"] == "lost"
    assert model([seen, stop], SETUP)["robots"]["Emil"]["state"] == "stopped"
    robot_failed = model([_failure("Pippi", "robot")], SETUP)
    assert robot_failed["robots"]["Pippi"]["state"] == "lost"
    assert "Pippi" in robot_failed["failed"]


def test_a_failure_and_a_switch_are_on_the_timeline_with_their_causes() -> None:
    """The failed resource is marked until it recovers; the switch changes the
    running configuration's id and cost; both are on the timeline, in order."""
    page = model([_failure(), _switch()], SETUP)
    assert page["failed"]["compass(Emil)"]["how"] == "injected"
    assert (page["configuration"], page["cost"], page["switches"]) == (1, 47.0, 1)
    kinds = [(e["seq"], e["kind"]) for e in page["timeline"]]
    assert kinds == [(1, "failure"), (2, "switch")]
    switch = page["timeline"][1]
    assert switch["cause"] == "compass(Emil) failed"
    assert switch["text"].startswith("switch 1 (compass(Emil) failed): cost 44 -> 47")
    assert switch["t"] == 5.0 and switch["robot"] == "Emil" and switch["cycle"] == 40
    assert page["timeline"][0]["cause"] == "injected, seen by Emil"
    recovery = Adaptation(
        robot="Emil",
        t=9.0,
        what="recovery",
        info=(("resource", "compass(Emil)"), ("kind", "functionality"), ("how", "probe")),
    )
    assert model([_failure(), _switch(), recovery], SETUP)["failed"] == {}


def test_nothing_admissible_halts_the_page_until_a_switch() -> None:
    """``no-configuration`` says why nothing runs; a later switch clears it."""
    none = Adaptation(
        robot="Emil",
        t=6.0,
        what="no-configuration",
        info=(("id", 2), ("cause", "camera(Emil) failed"), ("why", ["no camera left"])),
    )
    halted = model([_switch(), none], SETUP)
    assert halted["halted"] == "no camera left" and halted["cost"] is None
    assert model([_switch(), none, _switch(7.0)], SETUP)["halted"] is None


def test_calls_are_not_on_the_timeline_and_it_keeps_the_newest_entries() -> None:
    """Only what the timeline shows is kept, at most Limits.timeline entries."""
    events = [_call("ran")] + [_switch(float(i)) for i in range(10)]
    page = model(events, SETUP, Limits(timeline=4))
    assert [e["seq"] for e in page["timeline"]] == [7, 8, 9, 10]


def test_installs_are_on_the_timeline_only_away_from_the_coordinator() -> None:
    """On the coordinator a switch says it all; elsewhere the install is what is seen."""
    install = Adaptation(robot="Pippi", t=5.0, what="install", info=(("id", 1),))
    assert model([install], SETUP)["timeline"] == []
    member = Setup(title="x", robots=("Emil", "Pippi"), here=("Pippi",), coordinator="Emil")
    page = model([install], member)
    assert [e["kind"] for e in page["timeline"]] == ["install"] and page["decides"] is False


def test_the_page_follows_whoever_coordinates() -> None:
    """Pippi's page, a helper's: Emil coordinates (his switches installed
    here say so); Pippi takes over (her own ``takeover``), and her page
    decides from then on (her installs leave the timeline); she steps down
    for Rasmus, and it is a helper's again (5.5)."""
    member = Setup(title="x", robots=("Emil", "Pippi"), here=("Pippi",), coordinator="Pippi")

    def event(what: str, t: float, **info: object) -> Adaptation:
        return Adaptation(robot="Pippi", t=t, what=what, info=tuple(info.items()))

    run = [event("install", 1.0, id=1, epoch="1.a", leader="Emil")]
    assert (model(run, member)["coordinator"], model(run, member)["decides"]) == ("Emil", False)
    run.append(event("takeover", 2.0, epoch="2.b", after="Emil", step=0, goal="g", waited=0.3))
    run.append(event("install", 2.1, id=0, epoch="2.b", leader="Pippi"))
    page = model(run, member)
    assert (page["coordinator"], page["decides"]) == ("Pippi", True)
    assert [e["kind"] for e in page["timeline"]] == ["install", "takeover"]
    run.append(event("step-down", 3.0, leader="Rasmus", epoch="3.c", was="2.b"))
    page = model(run, member)
    assert (page["coordinator"], page["decides"]) == ("Rasmus", False)


def test_long_texts_from_the_run_are_clipped() -> None:
    """A cause of any length costs the page at most Limits.text characters."""
    long = Adaptation(robot="Emil", t=1.0, what="abort", info=(("reason", "x" * 5000),))
    entry = model([long], SETUP, Limits(text=50))["timeline"][0]
    assert len(entry["cause"]) == 50 and entry["cause"].endswith("…")
