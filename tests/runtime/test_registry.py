"""Declaring and finding actual functions (5.2.1); implementation files that
fail to import are reported as their own fault, never with a traceback."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from cfgplan.runtime import Registry, RunError, functionality
from tests.backends.support import EXAMPLE_IMPL

MODULE = """
from cfgplan.runtime import functionality

@functionality("camera")
def camera() -> str:
    return "image"

def helper() -> int:
    return 1
"""


def test_the_decorator_declares_and_the_function_still_runs() -> None:
    @functionality("measure-door", precondition=lambda door: door == "Door1")
    def measure(door: str, image: str) -> str:
        return f"{door} in {image}"

    registry = Registry([measure])
    impl = registry.lookup("measure-door")
    assert impl("Door1", "img") == "Door1 in img"
    assert impl.allowed("Door1") and not impl.allowed("Door2")


def test_a_missing_implementation_is_a_clear_error() -> None:
    registry = Registry.load(EXAMPLE_IMPL)
    with pytest.raises(RunError) as caught:
        registry.lookup("laser")
    message = str(caught.value)
    assert "no implementation of functionality laser" in message
    assert "camera" in message  # what there is instead
    assert caught.value.hint == 'declare one with @functionality("laser") from cfgplan.runtime'


def test_load_by_path_and_by_module_name(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "robot_impl_for_test.py").write_text(MODULE)
    by_path = Registry.load(tmp_path / "robot_impl_for_test.py")
    assert by_path.names() == ["camera"]
    monkeypatch.syspath_prepend(str(tmp_path))
    by_name = Registry.load("robot_impl_for_test")
    assert by_name.names() == ["camera"] and by_name.lookup("camera")() == "image"
    sys.modules.pop("robot_impl_for_test", None)


def test_loading_what_is_not_there() -> None:
    with pytest.raises(RunError, match="no such Python file"):
        Registry.load("no/such/impl.py")
    with pytest.raises(RunError, match="cannot import"):
        Registry.load("no_such_module_for_cfgplan")


def test_one_name_implemented_twice_is_an_error() -> None:
    a = functionality("camera")(lambda: 1)
    b = functionality("camera")(lambda: 2)
    with pytest.raises(RunError, match="implemented twice"):
        Registry([a, b])


def test_require_names_every_missing_implementation() -> None:
    registry = Registry([functionality("camera")(lambda: 1)], source="impl.py")
    registry.require(["camera", "camera"])
    with pytest.raises(RunError) as caught:
        registry.require(["laser", "camera", "sonar", "laser"])
    assert str(caught.value) == (
        "no implementation of functionalities laser, sonar in impl.py (implemented: camera)"
    )


# These used to escape registry.py as tracebacks.


def test_a_syntax_error_names_file_line_and_column(tmp_path: Path) -> None:
    impl = tmp_path / "broken_syntax.py"
    impl.write_text("from cfgplan.runtime import functionality\n\ndef camera(:\n    pass\n")
    with pytest.raises(RunError) as caught:
        Registry.load(impl)
    err = caught.value
    assert err.message.startswith(f"the implementations in {impl} do not compile: ")
    assert (err.file, err.line, err.column) == (str(impl), 3, 12)
    rendered = err.render().splitlines()
    assert rendered[0].startswith(f"{impl}:3:12: error: ")
    assert rendered[1:] == ["    3 | def camera(:", "      |            ^"]


def test_an_exception_at_import_names_the_file_and_line(tmp_path: Path) -> None:
    impl = tmp_path / "raises_at_import.py"
    impl.write_text("import math\n\nCALIBRATION = 1 / 0\n")
    with pytest.raises(RunError) as caught:
        Registry.load(impl)
    err = caught.value
    assert err.message == (
        f"importing the implementations {impl} raised ZeroDivisionError: division by zero"
    )
    assert (err.file, err.line) == (str(impl), 3)


def test_sys_exit_at_import_is_reported(tmp_path: Path) -> None:
    impl = tmp_path / "exits_at_import.py"
    impl.write_text("import sys\nsys.exit('no robot here')\n")
    with pytest.raises(RunError, match=r"called sys.exit\('no robot here'\)") as caught:
        Registry.load(impl)
    assert caught.value.line == 2


def test_an_exception_in_an_imported_module_by_name(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "impl_raising_by_name.py").write_text("raise RuntimeError('no camera attached')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(RunError, match="raised RuntimeError: no camera attached"):
        Registry.load("impl_raising_by_name")
    sys.modules.pop("impl_raising_by_name", None)


# -- signatures, checked before anything runs ----------------------------


def test_an_implementation_that_cannot_take_the_call_is_refused_naming_both() -> None:
    @functionality("measure-door")
    def measure(door: str) -> str:  # forgets the image input
        return door

    with pytest.raises(RunError) as caught:
        measure.check("F9: measure-door(Emil, Door1)", objects=1, inputs=1)
    error = caught.value
    assert error.message.startswith(
        "the function test_an_implementation_that_cannot_take_the_call_is_refused_naming_both."
        "<locals>.measure declared for measure-door cannot be called as "
        "F9: measure-door(Emil, Door1) calls it, with 1 object argument then 1 input "
        "(in :in order): too many positional arguments"
    )
    assert error.file == __file__
    assert error.line == measure.function.__code__.co_firstlineno
    measure.check("F9: measure-door(Emil, Door1)", objects=1, inputs=0)  # that call fits


def test_too_few_arguments_precondition_and_stop_are_checked_too() -> None:
    @functionality("cross-door", precondition=lambda: True, stop=lambda door: None)
    def cross(door: str, pos: object, orient: object, extra: object) -> None:
        return None

    with pytest.raises(RunError, match=r"with 1 object argument then 2 inputs .*missing"):
        cross.check("F3: cross-door(Pippi, Door1)", objects=1, inputs=2)
    precondition = r"the precondition \S*<lambda> declared .*: too many positional"
    with pytest.raises(RunError, match=precondition):
        cross.check("F3: cross-door(Pippi, Door1)", objects=1, inputs=None)


def test_variadic_and_defaulted_implementations_fit() -> None:
    @functionality("any")
    def anything(*args: object) -> None:
        return None

    @functionality("opt")
    def optional(a: object, b: object = None) -> None:
        return None

    anything.check("F1: any(R)", objects=0, inputs=5)
    optional.check("F1: opt(R, X)", objects=1, inputs=0)
    optional.check("F1: opt(R, X)", objects=1, inputs=1)
    with pytest.raises(RunError):
        optional.check("F1: opt(R)", objects=0, inputs=0)


def test_every_example_implementation_fits_its_domain() -> None:
    """The bundled implementations pass the check for each call of the cost-44 and
    cost-47 configurations (they run in tests/cli/test_run.py)."""
    registry = Registry.load(EXAMPLE_IMPL)
    fits = {"camera": (0, 0), "measure-door": (1, 1), "transform-info": (2, 4)}
    for name, (objects, inputs) in fits.items():
        registry.lookup(name).check(name, objects, inputs)


def test_an_implementation_spelt_otherwise_than_the_domain_is_pointed_at() -> None:
    """The file implements localize where the domain says localise: a "did you
    mean", at configuration time (require) and at a look-up alike."""
    registry = Registry([functionality("localize")(lambda: 1)], source="impl.py")
    for fail in (lambda: registry.require(["localise"]), lambda: registry.lookup("localise")):
        with pytest.raises(RunError) as caught:
            fail()
        assert str(caught.value) == (
            "no implementation of functionality localise in impl.py (implemented: localize)"
        )
        assert caught.value.hint == (
            "did you mean localize? (the domain names it localise: declare one with "
            '@functionality("localise") from cfgplan.runtime)'
        )
