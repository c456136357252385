"""The record of an emission (cfgplan/emission.py): ``sha256sum`` format,
leftovers removed, the user's files never touched."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from cfgplan.diagnostics import CfgplanError
from cfgplan.emission import RECORD, record_text, write_emission


def test_the_record_is_sha256sum_lines_in_the_order_written() -> None:
    text = record_text({"b.py": b"b\n", "a.py": b"a\n"})
    digest = {n: hashlib.sha256(d).hexdigest() for n, d in (("a.py", b"a\n"), ("b.py", b"b\n"))}
    assert text == f"{digest['b.py']}  b.py\n{digest['a.py']}  a.py\n"


def test_leftovers_of_the_earlier_emission_are_removed(tmp_path: Path) -> None:
    assert write_emission(tmp_path, {"x.py": b"1", "y.py": b"2"}, False) == []
    removed = write_emission(tmp_path, {"x.py": b"3"}, True)
    assert removed == [tmp_path / "y.py"]
    assert sorted(p.name for p in tmp_path.iterdir()) == [RECORD, "x.py"]
    assert (tmp_path / RECORD).read_text() == record_text({"x.py": b"3"})


def test_a_link_where_an_emitted_file_was_is_not_removed(tmp_path: Path) -> None:
    write_emission(tmp_path, {"x.py": b"1", "y.py": b"2"}, False)
    (tmp_path / "y.py").unlink()
    (tmp_path / "y.py").symlink_to(tmp_path / "x.py")
    with pytest.raises(CfgplanError, match=r"y\.py, which cfgplan did not write"):
        write_emission(tmp_path, {"x.py": b"3"}, True)
    assert (tmp_path / "y.py").is_symlink() and (tmp_path / "x.py").read_bytes() == b"1"


def test_a_record_changed_by_hand_is_refused_with_its_line(tmp_path: Path) -> None:
    write_emission(tmp_path, {"x.py": b"1"}, False)
    (tmp_path / RECORD).write_text("0000  ../../etc/passwd\n")
    with pytest.raises(CfgplanError, match=rf"{RECORD}:1: not a line of cfgplan's record"):
        write_emission(tmp_path, {"x.py": b"1"}, True)


def test_a_record_cannot_name_a_file_outside_the_folder(tmp_path: Path) -> None:
    out = tmp_path / "out"
    write_emission(out, {"x.py": b"1"}, False)
    victim = tmp_path / "victim.py"
    victim.write_bytes(b"v")
    digest = hashlib.sha256(b"v").hexdigest()
    (out / RECORD).write_text(f"{digest}  ../victim.py\n")
    with pytest.raises(CfgplanError, match="not a line"):
        write_emission(out, {"x.py": b"1"}, True)
    assert victim.read_bytes() == b"v"


def test_files_beside_the_emission_are_left_alone(tmp_path: Path) -> None:
    (tmp_path / "README").write_text("mine")
    write_emission(tmp_path, {"x.py": b"1"}, False)
    write_emission(tmp_path, {"z.py": b"1"}, True)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([RECORD, "README", "z.py"])
