"""Where the reader finds its grammar: the package data's folder, else
importlib.resources (cfgplan.syntax.reader.grammar_text)."""

from __future__ import annotations

from importlib import resources

import pytest

from cfgplan.syntax import reader


def _packaged() -> str:
    package, name = reader.GRAMMAR
    return resources.files(package).joinpath(name).read_text("utf-8")


def test_the_grammar_is_read_from_its_folder() -> None:
    assert reader.grammar_text.__wrapped__() == _packaged()
    assert "start: _form*" in _packaged()


@pytest.mark.parametrize("found", ["none", "no folder", "no file"])
def test_without_a_folder_to_read_importlib_resources_finds_it(
    found: str, monkeypatch: pytest.MonkeyPatch, tmp_path: object
) -> None:
    """No spec (as for a module that is not there), a spec without folders (a
    zipped package), or a folder without the file: the same text all the same."""

    class Spec:
        submodule_search_locations = [] if found == "no folder" else [str(tmp_path)]

    monkeypatch.setattr(reader, "find_spec", lambda name: None if found == "none" else Spec())
    assert reader.grammar_text.__wrapped__() == _packaged()
