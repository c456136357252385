"""The static checker's data-flow, variable and precondition checks (thesis
3.2-3.5, 4.4): one test per check, with the span it reports."""

from __future__ import annotations

from tests.check.checking import BASE, GOOD, at, loc, only, run

# -- data flow: what the endpoints produce and consume -------------------------


def test_channel_data_not_produced_by_functionality() -> None:
    text = BASE + GOOD.replace("?f1 ?f2 (image ?r)", "?f1 ?f2 (sound ?r)")
    found = run(text)
    d = [x for x in found if "not produced" in x.message]
    assert len(d) == 1
    assert d[0].message == "channel data (sound ?r) is not produced by ?f1 (camera ?r)"
    assert d[0].hint == "it produces (image ?r)"
    assert loc(d[0]) == "7:15"


def test_channel_data_not_consumed_by_functionality() -> None:
    text = BASE + GOOD.replace("(?f1 (camera ?r))", "(?f1 (measure-door ?r ?d))")
    text = text.replace("?f1 ?f2 (image ?r)", "?f1 ?f2 (pos ?r ?d)")
    d = only(run(text))
    assert d.message == "channel data (pos ?r ?d) is not consumed by ?f2 (measure-door ?r ?d)"
    assert d.hint == "it consumes (image ?r)"
    assert loc(d) == "7:15"


def test_descriptor_arity_must_match() -> None:
    text = BASE + GOOD.replace("?f1 ?f2 (image ?r)", "?f1 ?f2 (image ?r ?d)")
    found = run(text)
    assert [(d.message, loc(d)) for d in found] == [
        ("channel data (image ?r ?d) is not produced by ?f1 (camera ?r)", "7:15"),
        ("channel data (image ?r ?d) is not consumed by ?f2 (measure-door ?r ?d)", "7:15"),
    ]


def test_constants_of_a_call_must_match() -> None:
    method = GOOD.replace(":name '(get-door-info ?r ?d)", ":name '(get-door-info ?r)")
    method = method.replace("(door ?d)", "(door Door1)")
    method = method.replace("(measure-door ?r ?d)", "(measure-door ?r Door1)")
    method = method.replace("(?f2 (pos ?r ?d))", "(?f2 (pos ?r Door2))")
    text = BASE + method.replace("(?f2 (orient ?r ?d))", "(?f2 (orient ?r Door1))")
    d = only(run(text))
    assert d.message == ":out data (pos ?r Door2) is not produced by ?f2 (measure-door ?r Door1)"
    assert d.hint == "it produces (pos ?r Door1), (orient ?r Door1)"
    assert loc(d) == at(text, "(?f2 (pos ?r Door2))") == "6:10"


USES_METHOD = """\
(make-config-method :name '(do-cross ?r ?d)
  :precond '((robot ?r) (door ?d))
  :channels '(((local ?r) ?f1 ?f2 (pos ?r ?d)) ((local ?r) ?f1 ?f2 (orient ?r ?d)))
  :body '((?f1 (get-door-info ?r ?d)) (?f2 (cross-door ?r ?d))))
"""


def test_channel_from_method_uses_its_out_ports() -> None:
    assert run(BASE + GOOD + USES_METHOD) == []


def test_channel_data_not_on_out_port_of_method() -> None:
    text = BASE + GOOD.replace("(?f2 (orient ?r ?d))", "").replace(
        ":out '((?f2 (pos ?r ?d)) )", ":out '((?f2 (pos ?r ?d)))"
    )
    text += USES_METHOD
    d = only(run(text))
    assert d.message == "channel data (orient ?r ?d) is not produced by ?f1 (get-door-info ?r ?d)"
    assert d.hint == "it produces (pos ?r ?d) (the :out ports of its method versions)"
    assert loc(d) == at(text, "((local ?r) ?f1 ?f2 (orient") == "11:48"


def test_method_port_substitutes_the_version_parameters() -> None:
    # (get-door-info ?r Door1) produces (pos ?r Door1), never (pos ?r Door2).
    text = BASE + GOOD + USES_METHOD.replace("(get-door-info ?r ?d)", "(get-door-info ?r Door1)")
    text = text.replace("?f1 ?f2 (pos ?r ?d)", "?f1 ?f2 (pos ?r Door2)")
    found = run(text)
    d = only(found)
    assert d.message == (
        "channel data (pos ?r Door2) is not produced by ?f1 (get-door-info ?r Door1)"
    )
    assert d.hint == (
        "it produces (pos ?r Door1), (orient ?r Door1) (the :out ports of its method versions)"
    )
    assert loc(d) == at(text, "((local ?r) ?f1 ?f2 (pos") == "11:15"
    # The other ends match only for some bindings of the caller's ?d: warnings.
    assert [(x.message, loc(x)) for x in found if not x.is_error] == [
        (
            "channel data (pos ?r Door2) is consumed by ?f2 (cross-door ?r ?d) only if ?d = Door2",
            "11:15",
        ),
        (
            "channel data (orient ?r ?d) is produced by ?f1 (get-door-info ?r Door1) "
            "only if ?d = Door1",
            at(text, "((local ?r) ?f1 ?f2 (orient"),
        ),
    ]


def test_in_port_must_be_consumed() -> None:
    text = BASE + GOOD.replace(":out '(", ":in '((?f1 (image ?r))) :out '(")
    d = only(run(text))
    assert d.message == ":in data (image ?r) is not consumed by ?f1 (camera ?r)"
    assert d.hint == "it consumes nothing"
    assert loc(d) == at(text, "(?f1 (image ?r))") == "6:9"


def test_in_port_consumed_passes() -> None:
    text = BASE + GOOD.replace(":out '(", ":in '((?f2 (image ?r))) :out '(")
    assert run(text) == []


def test_out_port_must_be_produced() -> None:
    text = BASE + GOOD.replace("(?f2 (orient ?r ?d))", "(?f1 (orient ?r ?d))")
    d = only(run(text))
    assert d.message == ":out data (orient ?r ?d) is not produced by ?f1 (camera ?r)"
    assert loc(d) == at(text, "(?f1 (orient") == "6:28"


def test_match_only_by_equating_caller_variables_is_a_warning() -> None:
    text = BASE + GOOD.replace("?f1 ?f2 (image ?r)", "?f1 ?f2 (image ?d)")
    found = run(text)
    assert [(d.severity, d.message, loc(d)) for d in found] == [
        (
            "warning",
            "channel data (image ?d) is produced by ?f1 (camera ?r) only if ?r = ?d",
            "7:15",
        ),
        (
            "warning",
            "channel data (image ?d) is consumed by ?f2 (measure-door ?r ?d) only if ?r = ?d",
            "7:15",
        ),
    ]
    assert found[0].hint == "it produces (image ?r); check the variables of both"


def test_two_out_ports_with_same_descriptor() -> None:
    text = BASE + GOOD.replace("(?f2 (orient ?r ?d))", "(?f2 (pos ?r ?d))")
    d = only(run(text))
    assert d.message == "two :out ports give (pos ?r ?d); the first is at line 6"
    assert loc(d) == at(text, "(?f2 (pos ?r ?d))", 2) == "6:28"


# -- variables -------------------------------------------------------------------


def test_channel_variable_bound_by_nothing_is_an_error() -> None:
    """The planner cannot instantiate the channel, so every expansion
    of the method fails and configurations are lost without a word."""
    text = BASE + GOOD.replace("((local ?r) ?f1", "((local ?x) ?f1")
    d = only(run(text))
    assert d.message == (
        "?x is bound by neither the name nor a precondition of (get-door-info ?r ?d), "
        "so no expansion of it can be made"
    )
    assert loc(d) == "7:15"


def test_variable_bound_by_precondition_is_fine() -> None:
    text = BASE + GOOD.replace("((local ?r) ?f1", "((local ?x) ?f1").replace(
        "(door ?d))", "(door ?d) (robot ?x))"
    )
    assert run(text) == []


def test_body_call_variable_bound_by_nothing_is_an_error_once() -> None:
    text = BASE + GOOD.replace("(measure-door ?r ?d)", "(measure-door ?r ?z)")
    text = text.replace(
        ":out '((?f2 (pos ?r ?d)) (?f2 (orient ?r ?d)))", ":out '((?f2 (pos ?r ?z)))"
    )
    found = run(text)
    d = only(found)
    assert d.message.startswith("?z is bound by neither the name nor a precondition")
    assert loc(d) == at(text, "(?f2 (pos ?r ?z))") == "6:10"  # the first use, by position


def test_functionality_variable_not_in_name_is_a_warning() -> None:
    text = "(make-functionality :name '(camera ?r) :out '((image ?r ?q)))\n"
    d = only(run(text), "warning")
    assert d.message == (
        "?q in (image ?r ?q) occurs neither in the name (camera ?r) nor in a precondition"
    )
    assert loc(d) == at(text, "(image") == "1:47"


def test_functionality_output_bound_by_its_precondition_is_fine() -> None:
    """(loc ?r) with (in ?r ?room) produces (pos ?r ?room): the precondition
    binds ?room when the functionality is placed (4.5, 2a), so no warning."""
    text = "(make-functionality :name '(loc ?r) :precond '((in ?r ?room)) :out '((pos ?r ?room)))\n"
    assert run(text) == []


# -- preconditions ---------------------------------------------------------------


def test_eval_outside_safe_subset() -> None:
    text = BASE + GOOD.replace("(door ?d))", "(door ?d)\n  (eval (shell-command (quote rm))))")
    d = only(run(text))
    assert d.message.startswith("eval may not call shell-command")
    assert loc(d) == at(text, "(eval") == "6:3"


def test_eval_problems_each_reported() -> None:
    text = BASE + GOOD.replace("(door ?d))", "(door ?d) (eval (and (exit) (< ?r))) (eval foo))")
    found = [d for d in run(text) if d.is_error]
    assert [d.message.split(";")[0] for d in found] == [
        "eval may not call exit",
        "the bare symbol foo has no value",
    ]
    assert [loc(d) for d in found] == [at(text, "(eval (and"), at(text, "(eval foo")]


def test_eval_variable_never_bound() -> None:
    text = BASE + GOOD.replace("(door ?d))", "(door ?d) (eval (not (eql (quote ?r) (quote ?h)))))")
    d = only(run(text))
    assert d.message.startswith(
        "?h in (eval (not (eql (quote ?r) (quote ?h)))) is bound by neither"
    )
    assert "can never be bound" in d.message
    assert loc(d) == at(text, "(eval") == "5:36"


def test_negation_variable_never_bound() -> None:
    text = BASE + GOOD.replace("(door ?d))", "(door ?d) (not (in ?r ?room)))")
    d = only(run(text))
    assert d.message.startswith("?room in (not (in ?r ?room)) is bound by neither")
    assert loc(d) == at(text, "(not (in") == "5:36"


def test_negation_bound_by_a_later_atom_is_fine() -> None:
    text = BASE + GOOD.replace("(door ?d))", "(not (in ?r ?room)) (door ?d) (in ?d ?room))")
    assert run(text) == []
