"""The built wheel works on its own: installed into a fresh virtual environment and
imported from outside the repository, cfgplan finds its grammar as package data.

The repository is copied to a temporary folder first, so the build writes no
``build/`` or ``*.egg-info`` into the work tree. The wheel is built without
build isolation when this environment already satisfies ``[build-system]
requires`` (fast, offline), else with isolation (the build front end fetches
the requirements from the package index, as ``pip install`` does).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tomllib
import zipfile
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]
DOMAIN = ROOT / "domains" / "cross-door" / "domain.lisp"

_SKIP_COPY = shutil.ignore_patterns(
    ".git",
    ".venv",
    "venv",
    "build",
    "dist",
    "*.egg-info",
    "__pycache__",
    ".hypothesis",
    ".mypy_cache",
    ".ruff_cache",
    ".pytest_cache",
    ".benchmarks",
)


def _run(args: list[str], cwd: Path, env: dict[str, str] | None = None) -> str:
    done = subprocess.run(
        args, cwd=cwd, env=env, capture_output=True, text=True, timeout=300, check=False
    )
    assert done.returncode == 0, (
        f"{' '.join(args)} failed ({done.returncode}):\n{done.stdout}\n{done.stderr}"
    )
    return done.stdout


def _build_requirements_met() -> bool:
    """True if every ``[build-system] requires`` entry is installed here."""
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))
    for spec in pyproject["build-system"]["requires"]:
        req = Requirement(spec)
        try:
            version = metadata.version(req.name)
        except metadata.PackageNotFoundError:
            return False
        if version not in req.specifier:
            return False
    return True


def _clean_env() -> dict[str, str]:
    env = dict(os.environ)
    for var in ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "PYTHONUSERBASE"):
        env.pop(var, None)
    return env


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    src = tmp_path_factory.mktemp("src") / "cfgplan-src"
    shutil.copytree(ROOT, src, ignore=_SKIP_COPY)
    out = tmp_path_factory.mktemp("dist")
    args = [sys.executable, "-m", "build", "--wheel", "--outdir", str(out)]
    if _build_requirements_met():
        args.append("--no-isolation")
    _run([*args, str(src)], cwd=src, env=_clean_env())
    wheels = list(out.glob("cfgplan-*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


@pytest.fixture(scope="module")
def venv_python(wheel: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    venv = tmp_path_factory.mktemp("venv") / "env"
    _run(
        [sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", str(venv)],
        cwd=venv.parent,
    )
    python = venv / "bin" / "python"
    # If the tests themselves run in a virtual environment (as CI's .venv), the
    # new venv's "system" site-packages are the base interpreter's, which may
    # lack lark and pydantic: make this environment's site-packages visible too,
    # after the new venv's own. A path line in a .pth adds the folder without
    # running the .pth files in it (so no editable-install finder from there).
    own = Path(
        _run(
            [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
            cwd=venv.parent,
        ).strip()
    )
    parents = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    (own / "_parent_env.pth").write_text("\n".join(sorted(parents)) + "\n", "utf-8")
    _run(
        [str(python), "-m", "pip", "install", "--no-deps", "--no-index", "--quiet", str(wheel)],
        cwd=venv.parent,
        env=_clean_env(),
    )
    return python


def test_wheel_ships_every_module_and_the_grammar(wheel: Path) -> None:
    names = set(zipfile.ZipFile(wheel).namelist())
    assert "cfgplan/grammar/cfgplan.lark" in names, "the grammar is not shipped as package data"
    # cfgplan simulate finds its bundled scenarios, and their domains, in the package
    scenarios = ("cross-door/sim-6.2.2.toml", "carry-bar/sim-6.3.2.toml", "build-wall/sim-6.4.toml")
    for bundled in scenarios:
        assert f"cfgplan/domains/{bundled}" in names, bundled
    assert "cfgplan/domains/cross-door/domain-steps.lisp" in names
    source_modules = {
        p.relative_to(ROOT).as_posix()
        for p in (ROOT / "cfgplan").rglob("*.py")
        if "__pycache__" not in p.parts
    }
    missing = sorted(source_modules - names)
    assert not missing, f"modules left out of the wheel (add their packages): {missing}"


@pytest.mark.slow
def test_installed_wheel_imports_and_parses_outside_the_repo(
    venv_python: Path, tmp_path: Path
) -> None:
    probe = """
import json, sys
from importlib import resources
import cfgplan
from cfgplan.syntax.reader import domain_from, grammar_text, parse
text = open(sys.argv[1], encoding="utf-8").read()
domain = domain_from(parse(text, sys.argv[1]))
print(json.dumps({
    "cfgplan": cfgplan.__file__,
    "grammar": str(resources.files("cfgplan.grammar").joinpath("cfgplan.lark")),
    "grammar_text": grammar_text(),
    "functionalities": len(domain.functionalities),
    "methods": len(domain.methods),
    "prefix": sys.prefix,
}))
"""
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    assert ROOT not in outside.parents
    out = _run([str(venv_python), "-c", probe, str(DOMAIN)], cwd=outside, env=_clean_env())
    found = json.loads(out.strip().splitlines()[-1])
    venv = venv_python.parent.parent.resolve()

    assert Path(found["prefix"]).resolve() == venv
    cfgplan_file = Path(found["cfgplan"]).resolve()
    assert venv in cfgplan_file.parents, f"cfgplan imported from {cfgplan_file}, not the wheel"
    assert ROOT not in cfgplan_file.parents
    grammar = Path(found["grammar"]).resolve()
    assert venv in grammar.parents, f"grammar read from {grammar}, not the installed package"
    assert grammar.is_file()
    assert found["grammar_text"] == (ROOT / "grammar" / "cfgplan.lark").read_text("utf-8")
    assert (found["functionalities"], found["methods"]) == (9, 7)


def test_the_version_is_read_from_one_place() -> None:
    """``cfgplan --version`` prints :data:`cfgplan.__version__` without reading
    the package metadata (slow to import); the metadata is built from it, so
    the two agree (a stale install, made before the version changed, does not)."""
    import cfgplan

    assert metadata.version("cfgplan") == cfgplan.__version__
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))
    assert "version" not in pyproject["project"]
    assert "version" in pyproject["project"]["dynamic"]
    dynamic = pyproject["tool"]["setuptools"]["dynamic"]["version"]
    assert dynamic == {"attr": "cfgplan.__version__"}


def test_the_installed_wheel_says_its_version(
    wheel: Path, venv_python: Path, tmp_path: Path
) -> None:
    """The wheel's metadata carries cfgplan.__version__, and the installed
    package answers --version and --help (the help text pre-rendered from the
    typer app is shipped)."""
    import cfgplan

    meta = next(n for n in zipfile.ZipFile(wheel).namelist() if n.endswith(".dist-info/METADATA"))
    headers = zipfile.ZipFile(wheel).read(meta).decode("utf-8").splitlines()
    assert f"Version: {cfgplan.__version__}" in headers
    version = _run([str(venv_python), "-m", "cfgplan", "--version"], cwd=tmp_path, env=_clean_env())
    assert version == f"cfgplan {cfgplan.__version__}\n"
    shown = _run([str(venv_python), "-m", "cfgplan", "--help"], cwd=tmp_path, env=_clean_env())
    assert shown.startswith("Usage: cfgplan [OPTIONS] COMMAND [ARGS]...")
