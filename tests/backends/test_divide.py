"""Dividing per robot (5.1), against the individual descriptions of 5.4."""

from __future__ import annotations

from cfgplan.backends.divide import divide
from cfgplan.backends.sort import sort_functionalities
from cfgplan.configuration.model import Channel, Configuration, FunctionalityInstance
from tests.backends.support import cross_door_44, relabel, thesis_labels

# 5.4, the two individual configurations, as the thesis prints them (its
# "orient(Pippi Door1)" lacks a comma; bandwidths are not in domain.lisp).
THESIS_PIPPI = """\
(configuration Pippi
  Functionalities:
    F109: cross-door(Pippi, Door1)
    F116: compass(Pippi)
  Channels:
    global(Pippi, Emil, F116, F118, global-orient(Pippi))
    global(Emil, Pippi, F113, F109, pos(Pippi, Door1))
    global(Emil, Pippi, F113, F109, orient(Pippi, Door1))
)"""

THESIS_EMIL_CHANNELS = """\
    local(Emil, F114, F129, image(Emil))
    global(Pippi, Emil, F116, F118, global-orient(Pippi))
    local(Emil, F117, F118, global-orient(Emil))
    local(Emil, F114, F115, image(Emil))
    local(Emil, F115, F113, pos(Emil, Door1))
    local(Emil, F115, F113, orient(Emil, Door1))
    local(Emil, F118, F113, orient(Emil, Pippi))
    local(Emil, F129, F113, pos(Emil, Pippi))
    global(Emil, Pippi, F113, F109, pos(Pippi, Door1))
    global(Emil, Pippi, F113, F109, orient(Pippi, Door1))"""


def test_cross_door_44_divides_as_5_4() -> None:
    _, config = cross_door_44()
    labels = thesis_labels(config)
    pippi, emil = divide(config, sort_functionalities(config))
    assert (pippi.robot, emil.robot) == ("Pippi", "Emil")
    # functionalities keep the sorted order (5.4 prints the unsorted one for Pippi)
    assert [f.label for f in pippi.functionalities] == [labels["F116"], labels["F109"]]
    assert [f.label for f in emil.functionalities] == [
        labels[t] for t in ("F117", "F114", "F129", "F118", "F115", "F113")
    ]
    # channels keep the configuration's order; the global ones are on both robots
    pippi_text = pippi.text().splitlines()
    expected = relabel(THESIS_PIPPI, labels).splitlines()
    assert pippi_text[5:] == expected[5:]
    assert emil.text().splitlines()[9:-1] == relabel(THESIS_EMIL_CHANNELS, labels).splitlines()
    globals_ = [c for c in config.channels if c.kind == "global"]
    assert all(c in pippi.channels and c in emil.channels for c in globals_)
    assert len(pippi.channels) == 3 and len(emil.channels) == 10


def test_a_global_channel_with_both_ends_on_one_robot_is_there_once() -> None:
    """Build-a-wall (6.4) declares such channels: they stay global, on one robot."""
    f1 = FunctionalityInstance(label="F1", name="a", args=("Emil",))
    f2 = FunctionalityInstance(label="F2", name="b", args=("Emil",))
    ch = Channel(
        kind="global",
        source="F1",
        target="F2",
        source_robot="Emil",
        target_robot="Emil",
        data=("x",),
    )
    config = Configuration(functionalities=(f2, f1), channels=(ch,), cost=0)
    (emil,) = divide(config, (f1, f2))
    assert emil.channels == (ch,)
    assert emil.functionalities == (f1, f2)
