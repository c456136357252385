"""A griffe extension for the Python API page: cfgplan's docstrings are written
with reST roles (``:class:`~cfgplan.runtime.Robot```) and ``::`` before a
literal block; mkdocstrings reads Markdown, so each role becomes a code span
with the name as the reader sees it (``Robot``) and ``::`` a colon."""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?[a-z]+:`(~?)([^`<]+?)(?:\s*<[^>]*>)?`")


def markdown(text: str) -> str:
    """``text`` with roles as code spans and ``::`` as ``:``."""

    def role(match: re.Match[str]) -> str:
        name = match[2].strip()
        return f"`{name.rsplit('.', 1)[-1] if match[1] else name}`"

    text = _ROLE.sub(role, text)
    return re.sub(r"(\S)::(\s*\n)", r"\1:\2", text)


class RolesToCode(griffe.Extension):
    """Rewrite every docstring as it is loaded."""

    def on_instance(self, *, obj: Any, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = markdown(obj.docstring.value)
