"""The planner's shape, measured: ``python -m benchmarks.shape [PACKAGE]``.

Prints the number of modules of a package (``cfgplan/planner`` by default),
its lines that are neither blank nor comments (docstrings count), its classes,
and the cycles of its import graph (every import, type-only ones and those
inside functions included: a cycle hidden behind ``if TYPE_CHECKING:`` is
still one for the reader). ``--rev REV`` measures the package as git revision
REV has it, so that a change can be shown before and after.
"""

from __future__ import annotations

import argparse
import ast
import io
import subprocess
import tokenize
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def code_lines(text: str) -> int:
    """Lines holding a token other than a comment, a newline or indentation
    (a docstring's lines count: a string token spans them)."""
    lines: set[int] = set()
    skip = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT}
    for token in tokenize.generate_tokens(io.StringIO(text).readline):
        if token.type not in skip and token.type != tokenize.ENDMARKER:
            lines.update(range(token.start[0], token.end[0] + 1))
    return len(lines)


def imports(package: str, sources: dict[str, str]) -> dict[str, set[str]]:
    """Module -> the modules of ``package`` it imports anywhere in its text."""
    modules = {f"{package}.{Path(p).stem}" for p in sources if Path(p).stem != "__init__"}
    edges: dict[str, set[str]] = {}
    for path, text in sources.items():
        name = f"{package}.{Path(path).stem}"
        if name not in modules:
            continue
        found: set[str] = set()
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ImportFrom) and node.module and not node.level:
                named = [f"{node.module}.{a.name}" for a in node.names]
                found.update(t for t in named if t in modules)
                found.add(node.module)
            elif isinstance(node, ast.Import):
                found.update(a.name for a in node.names)
        edges[name] = {t for t in found if t in modules and t != name}
    return edges


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for child in sorted(edges[node]):
            if child not in index:
                visit(child)
                low[node] = min(low[node], low[child])
            elif child in stack:
                low[node] = min(low[node], index[child])
        if low[node] == index[node]:
            component = []
            while True:
                top = stack.pop()
                component.append(top)
                if top == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(edges):
        if node not in index:
            visit(node)
    return found


def sources(folder: str, rev: str | None) -> dict[str, str]:
    """The package's ``.py`` files and their text, in the work tree or at ``rev``."""
    if rev is None:
        return {str(p): p.read_text(encoding="utf-8") for p in sorted((ROOT / folder).glob("*.py"))}
    listed = subprocess.run(
        ["git", "-C", str(ROOT), "ls-tree", "--name-only", f"{rev}:{folder}"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.split()
    return {
        name: subprocess.run(
            ["git", "-C", str(ROOT), "show", f"{rev}:{folder}/{name}"],
            check=True,
            capture_output=True,
            text=True,
        ).stdout
        for name in listed
        if name.endswith(".py")
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("folder", nargs="?", default="cfgplan/planner")
    parser.add_argument("--rev", help="measure the package at this git revision")
    args = parser.parse_args()
    texts = sources(args.folder, args.rev)
    package = args.folder.replace("/", ".")
    edges = imports(package, texts)
    modules = [p for p in texts if Path(p).stem != "__init__"]
    lines = sum(code_lines(t) for t in texts.values())
    classes = sum(
        isinstance(n, ast.ClassDef) for t in texts.values() for n in ast.walk(ast.parse(t))
    )
    print(f"{args.folder} at {args.rev or 'the work tree'}")
    print(f"modules (without __init__): {len(modules)}")
    print(f"lines neither blank nor comment (docstrings count): {lines}")
    print(f"classes: {classes}")
    found = cycles(edges)
    print(f"import cycles: {len(found)}")
    for component in found:
        print("  " + " ".join(m.rsplit(".", 1)[1] for m in component))


if __name__ == "__main__":
    main()
