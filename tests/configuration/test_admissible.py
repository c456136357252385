"""The independent admissibility checker (thesis 3.5, 4.6) against the planner.

Every configuration the planner returns for a bundled domain and state must
pass :func:`problems`; configurations broken on purpose must fail it for the
reason that was broken in.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path

import pytest

from cfgplan.configuration.admissible import problems
from cfgplan.configuration.cost import Weights
from cfgplan.configuration.model import Assignment, Channel, Configuration, FunctionalityInstance
from cfgplan.ir.model import Atom, Eval, Negation, State
from cfgplan.planner import plan
from cfgplan.problem import Problem, load
from tests.backends.support import BANDWIDTH_DOMAIN, DOMAINS, MEDIA_STATE, bundled_pairs

PAIRS = bundled_pairs()


@cache
def solved(domain: str, state: str) -> tuple[Problem, tuple[Configuration, ...]]:
    problem = load(DOMAINS / domain, DOMAINS / state)
    configs, _ = plan(problem.task, problem.goal_call, limit=None, distinct=False)
    return problem, tuple(configs)


def test_every_bundled_domain_is_covered() -> None:
    assert len(PAIRS) >= 7
    assert {d.parent.name for d, _ in PAIRS} == {"build-wall", "carry-bar", "cross-door", "docking"}
    assert any(s.name == MEDIA_STATE for _, s in PAIRS)


@pytest.mark.parametrize(
    ("domain", "state"),
    [(d, s) for d, s in PAIRS],
    ids=[f"{d.parent.name}/{d.stem}+{s.stem}" for d, s in PAIRS],
)
def test_planned_configurations_are_admissible(domain: Path, state: Path) -> None:
    problem, configs = solved(str(domain.relative_to(DOMAINS)), str(state.relative_to(DOMAINS)))
    if not configs:
        pytest.skip("the planner finds no configuration for this pair")
    for config in configs:
        assert problems(config, problem.domain, problem.state) == [], config.derivation
        assert problems(config, problem.domain, problem.state, problem.task.weights) == []


def test_weighted_configurations_are_admissible() -> None:
    weights = Weights(robot=2, global_=5, local=0, functionality=0.5)
    problem = load(
        DOMAINS / "carry-bar" / "domain.lisp",
        DOMAINS / "carry-bar" / "state-6.3.2.lisp",
        None,
        weights,
    )
    configs, _ = plan(problem.task, problem.goal_call, limit=None, distinct=False)
    assert configs
    for config in configs:
        assert problems(config, problem.domain, problem.state, weights) == []
        # The default weights do not price it so.
        assert any(
            p.startswith("cost:")
            for p in problems(config, problem.domain, problem.state, Weights())
        )


# -- breaking real configurations ---------------------------------------------


def cross_door() -> tuple[Problem, Configuration]:
    """The cost-44 configuration of 4.6 (Fig. 4.3), without media."""
    problem, configs = solved("cross-door/domain.lisp", "cross-door/state-6.2.2-step1.lisp")
    assert configs[0].cost == 44
    return problem, configs[0]


def cross_door_media() -> tuple[Problem, Configuration]:
    """The same with the bandwidths and media of 4.6."""
    problem, configs = solved(f"cross-door/{BANDWIDTH_DOMAIN}", f"cross-door/{MEDIA_STATE}")
    assert configs[0].cost == 44
    assert configs[0].media
    return problem, configs[0]


def check(problem: Problem, config: Configuration, state: State | None = None) -> list[str]:
    return problems(config, problem.domain, state or problem.state)


def with_channels(config: Configuration, channels: list[Channel]) -> Configuration:
    return config.model_copy(update={"channels": tuple(channels)})


def reported(found: list[str], condition: str, *words: str) -> bool:
    return any(p.startswith(condition + ":") and all(w in p for w in words) for p in found)


def test_the_unbroken_configurations_pass() -> None:
    for problem, config in (cross_door(), cross_door_media()):
        assert check(problem, config) == []


def test_dropped_channel_leaves_an_input_unfed() -> None:
    problem, config = cross_door()
    channels = list(config.channels)
    dropped = next(c for c in channels if c.data == ("image", "Emil"))
    channels.remove(dropped)
    found = check(problem, with_channels(config, channels))
    target = config.functionality(dropped.target)
    assert reported(found, "information", "(image Emil)", target.name, "fed by no channel")
    assert reported(found, "cost")  # one local channel fewer


def test_flipped_source_robot_is_a_location_problem() -> None:
    problem, config = cross_door()
    channels = list(config.channels)
    index = next(i for i, c in enumerate(channels) if c.kind == "global")
    wrong = "Emil" if channels[index].source_robot == "Pippi" else "Pippi"
    channels[index] = channels[index].model_copy(update={"source_robot": wrong})
    found = check(problem, with_channels(config, channels))
    assert reported(found, "location", f"channel {index}", f"source_robot is {wrong}")
    assert not reported(found, "information")


def test_local_channel_between_two_robots() -> None:
    problem, config = cross_door()
    channels = list(config.channels)
    index = next(i for i, c in enumerate(channels) if c.kind == "global")
    channels[index] = channels[index].model_copy(update={"kind": "local"})
    found = check(problem, with_channels(config, channels))
    assert reported(found, "location", f"channel {index}", "a local channel joins two robots")


def test_changed_cost() -> None:
    problem, config = cross_door()
    found = check(problem, config.model_copy(update={"cost": 43.0}))
    assert found == [
        "cost: the configuration says 43, but its parts cost 44 (2 robots, 3 global and "
        "7 local channels, 8 functionalities; weights robot=10,global=3,local=1,functionality=1,"
        "device=10)"
    ]


def test_changed_weights_change_the_cost() -> None:
    problem, config = cross_door()
    heavy = config.model_copy(update={"weights": Weights(robot=20)})
    assert reported(check(problem, heavy), "cost", "64")
    # Asking for other weights than the configuration records is a problem too.
    found = problems(config, problem.domain, problem.state, Weights(local=2))
    assert reported(found, "cost", "records weights")


def test_duplicate_channel() -> None:
    problem, config = cross_door()
    channels = [*config.channels, config.channels[2]]
    found = check(problem, with_channels(config, channels))
    assert reported(found, "duplicate", f"channel {len(channels) - 1}", "repeats channel 2")


def test_reversed_channel_makes_a_cycle() -> None:
    problem, config = cross_door()
    first = config.channels[0]
    back = first.model_copy(
        update={
            "source": first.target,
            "target": first.source,
            "source_robot": first.target_robot,
            "target_robot": first.source_robot,
        }
    )
    found = check(problem, with_channels(config, [*config.channels, back]))
    assert reported(found, "cycle", first.source, first.target)
    # The reversed channel also carries data its ends neither produce nor consume.
    assert reported(found, "information", "does not produce it")
    assert reported(found, "information", "does not consume it")


def test_channel_to_a_missing_label() -> None:
    problem, config = cross_door()
    channels = list(config.channels)
    channels[0] = channels[0].model_copy(update={"target": "F999"})
    found = check(problem, with_channels(config, channels))
    assert reported(found, "channel", "channel 0", "target F999 is no functionality")


def test_duplicate_label() -> None:
    problem, config = cross_door()
    functionalities = list(config.functionalities)
    functionalities[1] = functionalities[1].model_copy(update={"label": functionalities[0].label})
    found = check(problem, config.model_copy(update={"functionalities": tuple(functionalities)}))
    assert reported(found, "labels", f"label {functionalities[0].label} names both")


def test_unknown_functionality() -> None:
    problem, config = cross_door()
    extra = FunctionalityInstance(label="F99", name="camera", args=("Emil", "Pippi"))
    found = check(
        problem, config.model_copy(update={"functionalities": (*config.functionalities, extra)})
    )
    assert reported(found, "domain", "camera(Emil, Pippi)", "2 argument(s)")


def test_causal_precondition_fails_in_another_state() -> None:
    problem, config = cross_door()
    assert any(f.name == "measure-robot-orient-compass" for f in config.functionalities)
    facts = tuple(a for a in problem.state.facts if str(a) != "(compass Pippi)")
    assert len(facts) == len(problem.state.facts) - 1
    found = check(problem, config, problem.state.model_copy(update={"facts": facts}))
    assert found == [
        "causal: the preconditions of F12: measure-robot-orient-compass(Emil, Pippi) do not "
        "hold in the state: (compass ?rh1) (compass ?r)"
    ]


def test_negated_and_eval_preconditions() -> None:
    problem, config = cross_door()
    # camera has no precondition in the domain; give it one with a negation and an eval.
    domain = problem.domain
    camera = domain.functionality(("camera", 1))
    assert camera is not None
    guarded = camera.model_copy(
        update={
            "precond": (
                Atom(predicate="in", args=("?r", "?room")),
                Negation(atom=Atom(predicate="dark", args=("?room",))),
                Eval(expr=["not", ["eql", ["quote", "?r"], ["quote", "Pippi"]]]),
            )
        }
    )
    changed = domain.model_copy(
        update={
            "functionalities": tuple(guarded if f is camera else f for f in domain.functionalities)
        }
    )
    assert problems(config, changed, problem.state) == []  # Emil's camera, Room1 lit
    dark = problem.state.model_copy(
        update={"facts": (*problem.state.facts, Atom(predicate="dark", args=("Room1",)))}
    )
    assert reported(problems(config, changed, dark), "causal", "camera(Emil)")


# -- communication ----------------------------------------------------------------


def test_wrong_direction_medium() -> None:
    problem, config = cross_door_media()
    media = problem.state.media
    first = config.media[0]
    other = next(j for j, m in enumerate(media) if j != first.medium)
    broken = config.model_copy(
        update={"media": (Assignment(channel=first.channel, medium=other), *config.media[1:])}
    )
    found = check(problem, broken)
    ch = config.channels[first.channel]
    assert found == [
        f"communication: channel {first.channel} ({ch.kind} {ch.source} -> {ch.target} "
        f"({' '.join(ch.data)})) goes from {ch.source_robot} to {ch.target_robot} but is "
        f"assigned to medium {other} (socket {media[other].sender}->{media[other].receiver}, "
        "capacity 200)"
    ]


def test_shrunk_capacity_overflows() -> None:
    problem, config = cross_door_media()
    media = tuple(m.model_copy(update={"capacity": 25.0}) for m in problem.state.media)
    found = check(problem, config, problem.state.model_copy(update={"media": media}))
    # Emil -> Pippi carries pos (20) and orient (10) of the door: 30 > 25.
    assert found == [
        "communication: medium 1 (socket Emil->Pippi, capacity 25) carries 30, "
        "more than its capacity 25"
    ]


def test_missing_assignment() -> None:
    problem, config = cross_door_media()
    broken = config.model_copy(update={"media": config.media[1:]})
    found = check(problem, broken)
    assert reported(found, "communication", f"channel {config.media[0].channel}", "no medium")


def test_assignment_where_none_is_needed() -> None:
    problem, config = cross_door_media()
    local = next(i for i, c in enumerate(config.channels) if c.kind == "local")
    broken = config.model_copy(
        update={"media": (*config.media, Assignment(channel=local, medium=0))}
    )
    assert reported(check(problem, broken), "communication", f"channel {local}", "needs none")


def test_media_without_media_in_the_state() -> None:
    problem, config = cross_door_media()
    found = check(problem, config, problem.state.model_copy(update={"media": ()}))
    assert reported(found, "communication", "declares none")


def test_without_media_no_assignment_is_needed() -> None:
    problem, config = cross_door()
    assert not config.media
    assert check(problem, config) == []
