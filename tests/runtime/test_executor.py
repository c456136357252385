"""Running the cost-44 configuration of 4.6 in process, and cutting a channel."""

from __future__ import annotations

from collections import Counter

from cfgplan.backends.wiring import deploy
from cfgplan.runtime import (
    Implementation,
    InProcessTransport,
    Registry,
    Society,
    build,
    society,
    summary,
)
from cfgplan.runtime.channel import channel_id
from tests.backends.support import EXAMPLE_IMPL, cross_door_44


def _counting(registry: Registry, calls: Counter[str]) -> Registry:
    """The same implementations, counting how often each actually runs."""

    def counted(impl: Implementation) -> Implementation:
        def run(*args: object) -> object:
            calls[impl.name] += 1
            return impl(*args)

        return Implementation(impl.name, run, impl.precondition)

    return Registry(counted(registry.lookup(n)) for n in registry.names())


class Cut(InProcessTransport):
    """A transport that loses everything sent on one channel."""

    def __init__(self, cut: str) -> None:
        super().__init__()
        self.cut = cut

    def send(self, channel_id: str, robot: str, value: object) -> None:
        if channel_id != self.cut:
            super().send(channel_id, robot, value)


def test_all_functionalities_run_and_the_action_gets_data_from_cycle_two() -> None:
    problem, config = cross_door_44()
    calls: Counter[str] = Counter()
    running = society(deploy(config, problem.domain), _counting(Registry.load(EXAMPLE_IMPL), calls))
    running.run(4)
    assert [r.name for r in running.robots] == ["Pippi", "Emil"]
    assert calls["camera"] == calls["transform-info"] == 4
    assert calls["compass"] == 8  # Emil's and Pippi's
    assert calls["cross-door"] == 3  # the door info crosses to Pippi after Emil's first cycle
    assert running.transport is not None and running.transport.undelivered == 0


def test_a_cut_channel_makes_the_wrappers_skip() -> None:
    """Pippi's global-orient never reaches Emil: measure-robot-orient-compass,
    then transform-info, then cross-door wait; their functions never run."""
    problem, config = cross_door_44()
    (compass_pippi,) = [c for c in config.channels if c.data == ("global-orient", "Pippi")]
    transport = Cut(channel_id(compass_pippi.source, compass_pippi.target, compass_pippi.data))
    calls: Counter[str] = Counter()
    registry = _counting(Registry.load(EXAMPLE_IMPL), calls)
    running = Society([build(p, registry, transport) for p in deploy(config, problem.domain)])
    running.run(3)
    assert calls["camera"] == 3 and calls["measure-door"] == 3 and calls["compass"] == 6
    assert calls["measure-robot-orient-compass"] == 0
    assert calls["transform-info"] == 0 and calls["cross-door"] == 0
    waiting = {e.name: e.waiting for e in running.events if e.status == "waiting"}
    assert waiting["measure-robot-orient-compass"] == (("global-orient", "Pippi"),)
    assert waiting["transform-info"] == (("orient", "Emil", "Pippi"),)
    assert waiting["cross-door"] == (("pos", "Pippi", "Door1"), ("orient", "Pippi", "Door1"))
    lines = summary(running.events)
    assert any(
        "measure-robot-orient-compass(Emil, Pippi): ran in 0 of 3 cycles; "
        "waits for global-orient(Pippi)" in line
        for line in lines
    )
