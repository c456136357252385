"""The analysed grammar is cached between runs (building the LALR
tables was a tenth of ``cfgplan plan``): a parser read from the cache reads
as one built from the grammar, positions and errors alike, and a cache that
cannot be read or written is only slower."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from cfgplan.syntax import reader
from tests.backends.support import ROOT

CROSS = ROOT / "domains" / "cross-door"
BROKEN = "(make-functionality :name (camera ?r)\n  :out ((image ?r)) :cost )"
"""A syntax error on line 2: Lark's error, from either parser, says where."""


def _read(cache: Path | None, text: str) -> list[object]:
    """What a parser built with ``cache`` makes of ``text``: its forms, or the
    syntax error (message and where)."""
    parser, transformer = reader.build_parser(cache)
    transformer.begin("f.lisp")
    try:
        return list(parser.parse(text).children)
    except Exception as exc:  # compared as what it says and where
        return [type(exc).__name__, getattr(exc, "line", None), getattr(exc, "column", None)]


def _texts() -> list[str]:
    return [
        (CROSS / "domain.lisp").read_text("utf-8"),
        (CROSS / "state-6.2.2-step1.lisp").read_text("utf-8"),
        BROKEN,
    ]


def test_a_cached_parser_reads_as_a_built_one(tmp_path: Path) -> None:
    cache = tmp_path / "sub" / "parser.lark"
    for text in _texts():
        expected = _read(None, text)
        assert expected  # a domain, a state, an error
        assert _read(cache, text) == expected  # built, then written
        assert cache.is_file()
        before = cache.stat().st_mtime_ns
        os.utime(cache, ns=(before - 10**9, before - 10**9))  # a second older
        assert _read(cache, text) == expected  # read from the file ...
        assert cache.stat().st_mtime_ns == before - 10**9  # ... not written again


def test_spans_survive_the_cache(tmp_path: Path) -> None:
    cache = tmp_path / "parser.lark"
    reader.build_parser(cache)
    text = _texts()[0]
    spans = [getattr(form, "span", None) for form in _read(cache, text)]
    assert None not in spans
    assert spans == [getattr(form, "span", None) for form in _read(None, text)]


@pytest.mark.parametrize(
    "content", [b"", b"garbage\n", b"0" * 64 + b"\n\x80\x04K.", b"\x00" * 4096]
)
def test_a_bad_cache_file_is_built_again(tmp_path: Path, content: bytes) -> None:
    cache = tmp_path / "parser.lark"
    cache.write_bytes(content)
    text = _texts()[0]
    assert _read(cache, text) == _read(None, text)
    assert cache.read_bytes() != content  # written again, whole


def test_a_cache_that_cannot_be_written_is_skipped(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    text = _texts()[1]
    assert _read(blocker / "parser.lark", text) == _read(None, text)
    folder = tmp_path / "folder"
    folder.mkdir()
    assert _read(folder, text) == _read(None, text)  # a folder where the file goes


def test_the_cache_lives_in_the_users_cache_folder(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_CACHE_HOME", "/somewhere/cache")
    found = reader.cache_file()
    assert found is not None and found.parent == Path("/somewhere/cache/cfgplan")
    assert found.name.startswith("parser-") and found.suffix == ".lark"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/cache")  # ignored, as XDG says
    assert reader.cache_file() is None
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", "/home/someone")
    assert reader.cache_file() == Path("/home/someone/.cache/cfgplan", found.name)


def test_reading_files_uses_the_cached_parser(tmp_path: Path) -> None:
    """The whole reader, in a fresh process, writes the cache and then reads it."""
    code = (
        "from cfgplan.syntax.reader import read_domain, read_state\n"
        f"d, _ = read_domain({str(CROSS / 'domain.lisp')!r})\n"
        f"s, _ = read_state({str(CROSS / 'state-6.2.2-step1.lisp')!r})\n"
        "print(d.model_dump_json(), s.model_dump_json())\n"
    )
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path)}
    runs = [
        subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=60
        )
        for _ in range(2)
    ]
    assert [r.returncode for r in runs] == [0, 0], runs[0].stderr
    assert runs[0].stdout == runs[1].stdout
    assert len(list((tmp_path / "cfgplan").glob("parser-*.lark"))) == 1
