"""Declaring and finding actual functions (5.2.1)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from cfgplan.diagnostics import CfgplanError
from cfgplan.runtime import Registry, functionality
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
    with pytest.raises(CfgplanError) as caught:
        registry.lookup("laser")
    message = str(caught.value)
    assert "no implementation of functionality laser" in message
    assert "camera" in message  # what there is instead
    assert (
        caught.value.diagnostics[0].hint
        == 'declare one with @functionality("laser") from cfgplan.runtime'
    )


def test_load_by_path_and_by_module_name(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    (tmp_path / "robot_impl_for_test.py").write_text(MODULE)
    by_path = Registry.load(tmp_path / "robot_impl_for_test.py")
    assert by_path.names() == ["camera"]
    monkeypatch.syspath_prepend(str(tmp_path))
    by_name = Registry.load("robot_impl_for_test")
    assert by_name.names() == ["camera"] and by_name.lookup("camera")() == "image"
    sys.modules.pop("robot_impl_for_test", None)


def test_loading_what_is_not_there() -> None:
    with pytest.raises(CfgplanError, match="no such Python file"):
        Registry.load("no/such/impl.py")
    with pytest.raises(CfgplanError, match="cannot import"):
        Registry.load("no_such_module_for_cfgplan")


def test_one_name_implemented_twice_is_an_error() -> None:
    a = functionality("camera")(lambda: 1)
    b = functionality("camera")(lambda: 2)
    with pytest.raises(CfgplanError, match="implemented twice"):
        Registry([a, b])


def test_require_names_every_missing_implementation() -> None:
    registry = Registry([functionality("camera")(lambda: 1)], source="impl.py")
    registry.require(["camera", "camera"])
    with pytest.raises(CfgplanError) as caught:
        registry.require(["laser", "camera", "sonar", "laser"])
    assert str(caught.value) == (
        "no implementation of functionalities laser, sonar in impl.py (implemented: camera)"
    )
