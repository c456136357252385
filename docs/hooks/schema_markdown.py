"""Markdown for the generated reference pages (:mod:`reference`, the MkDocs hook):
help and docstring text made safe for Markdown, and JSON Schemas (of pydantic
models) as tables, one per object, with the schema itself folded below."""

from __future__ import annotations

import inspect
import json
import re
from collections.abc import Sequence
from typing import Any

from pydantic import BaseModel

# -- Markdown helpers --------------------------------------------------------


def prose(text: str) -> str:
    """Docstring or help text as Markdown: reST roles and double backticks
    become code spans; characters Markdown would take as markup are escaped."""
    text = re.sub(r":[a-z]+:`~?([^`]+)`", r"``\1``", text)
    out = []
    for i, piece in enumerate(re.split(r"``(.+?)``|`([^`]+)`", text, flags=re.S)):
        if piece is None:
            continue
        if i % 3:  # inside a code span
            out.append(f"`{piece}`")
        else:
            piece = re.sub(r"([\\*_\[\]#])", r"\\\1", piece)
            out.append(piece.replace("<", "&lt;").replace(">", "&gt;"))
    return "".join(out)


def cell(text: str) -> str:
    """Text for a table cell: one line, pipes escaped."""
    return " ".join(text.split()).replace("|", "\\|")


def paragraphs(text: str) -> str:
    """A docstring's paragraphs, each on one line of Markdown."""
    parts = [" ".join(p.split()) for p in re.split(r"\n\s*\n", text.strip())]
    return "\n\n".join(prose(p) for p in parts if p)


# -- JSON Schema pages -----------------------------------------------------------


def _ref(node: dict[str, Any]) -> str:
    name = str(node["$ref"]).rsplit("/", 1)[-1]
    return f"[{name}](#{name.lower()})"


def type_of(node: dict[str, Any] | bool) -> str:
    """A schema node as a short phrase (Markdown): ``list of string``."""
    if isinstance(node, bool):
        return "any JSON value" if node else "nothing"
    if "$ref" in node:
        return _ref(node)
    if "const" in node:
        return f"`{json.dumps(node['const'])}`"
    if "enum" in node:
        return " or ".join(f"`{json.dumps(v)}`" for v in node["enum"])
    choices = node.get("anyOf") or node.get("oneOf")
    if choices:
        return " or ".join(type_of(n) for n in choices)
    if "allOf" in node and len(node["allOf"]) == 1:
        return type_of(node["allOf"][0])
    kind = node.get("type")
    if kind == "array":
        if "prefixItems" in node:
            return "[" + ", ".join(type_of(n) for n in node["prefixItems"]) + "]"
        item = type_of(node.get("items", {}))
        return f"list of ({item})" if " or " in item else f"list of {item}"
    if kind == "object" and "properties" not in node:
        keys = type_of(node["propertyNames"]) if "propertyNames" in node else "string"
        return f"map of {keys} to {type_of(node.get('additionalProperties', {}))}"
    if isinstance(kind, str):
        return kind
    return "any JSON value"


def _limits(node: dict[str, Any]) -> str:
    marks = {"minimum": "≥", "exclusiveMinimum": ">", "maximum": "≤", "exclusiveMaximum": "<"}
    found = [f"{sign} {node[key]}" for key, sign in marks.items() if key in node]
    return f" ({', '.join(found)})" if found else ""


def _optional(prop: dict[str, Any]) -> dict[str, Any]:
    """A key that may be left out, without the ``null`` its default stands
    for: such a key is left out, never written ``null`` (nor can TOML write it)."""
    choices = prop.get("anyOf")
    if prop.get("default", 0) is not None or not choices:
        return prop
    rest = [c for c in choices if c != {"type": "null"}]
    return {**prop, "anyOf": rest} if len(rest) > 1 else {**prop, **rest[0], "anyOf": [rest[0]]}


def _need(key: str, prop: dict[str, Any], required: set[str]) -> str:
    if key in required:
        return "yes"
    default = prop.get("default")
    if default is None or isinstance(default, dict) or default in ([], ""):
        return "no"
    return f"no (default `{json.dumps(default)}`)"


def definition(name: str, node: dict[str, Any], notes: dict[str, str] | None = None) -> list[str]:
    """One object of a schema: its description, then a table of its keys
    (``notes``: a description for keys the schema has none for)."""
    lines = [f"### {name} {{#{name.lower()}}}", ""]
    if node.get("description"):
        lines += [paragraphs(node["description"]), ""]
    if "properties" not in node:
        return [*lines, type_of(node), ""]
    required = set(node.get("required", ()))
    lines += ["| key | type | required | description |", "|---|---|---|---|"]
    for key, prop in node["properties"].items():
        shown = prop if key in required else _optional(prop)
        what = type_of(shown) + _limits(prop)
        about = prop.get("description") or (notes or {}).get(key, "")
        need = _need(key, prop, required)
        lines.append(f"| `{key}` | {cell(what)} | {cell(need)} | {cell(prose(about))} |")
    return [*lines, ""]


def schema_section(
    schema: dict[str, Any],
    order: Sequence[str] = (),
    notes: dict[str, dict[str, str]] | None = None,
) -> list[str]:
    """Every definition of ``schema`` (those named in ``order`` first), then the
    schema itself, folded."""
    defs: dict[str, Any] = schema.get("$defs", {})
    names = [n for n in order if n in defs] + sorted(n for n in defs if n not in order)
    lines: list[str] = []
    for name in names:
        lines += definition(name, defs[name], (notes or {}).get(name))
    body = json.dumps(schema, indent=2, ensure_ascii=False)
    lines += ['??? note "The JSON Schema"', "", "    ```json"]
    lines += [f"    {line}" for line in body.splitlines()]
    return [*lines, "    ```", ""]


def comments(model: type[BaseModel]) -> dict[str, str]:
    """The comment at the end of each field's line in the model's source
    (``passage: float  # degrees``), by the field's key in the file."""
    found: dict[str, str] = {}
    for line in inspect.getsource(model).splitlines():
        match = re.match(r"\s+(\w+): .*?  # (.+)$", line)
        if match and match[1] in model.model_fields:
            field = model.model_fields[match[1]]
            found[field.alias or match[1]] = match[2].strip()
    return found
