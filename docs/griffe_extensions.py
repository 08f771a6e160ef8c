"""Griffe extension of the documentation site (mkdocs.yml, the Python handler's
``extensions``): the package's docstrings as the site shows them.

* Cross-references written in the Sphinx roles the docstrings use (``:func:`read_run```,
  ``:class:`~pneumaquad.core.bank.ActuatorBank```, ``:mod:`.stability```) become links to
  the documented object, resolved in the scope of the docstring that names them (its
  imports included); a name the site does not document is shown as code. A ``~`` shows
  the last component only, as in Sphinx.
* A module-level or class attribute documented by ``#:`` comments above it (the
  package's convention for constants) gets that text as its docstring.
"""

from __future__ import annotations

import ast
import re
from html import escape
from typing import Any

import griffe

_ROLE = re.compile(  # a role may be broken over lines; `title <target>` names a target
    r":(?:py:)?(?:func|class|meth|attr|data|mod|obj|exc|const):`(?P<tilde>~?)"
    r"(?P<name>[^`<]+?)(?P<call>\(\))?(?:\s*<(?P<target>[^`<>]+)>)?`"
)


def _identifier(obj: griffe.Object, name: str) -> str | None:
    """The full path of ``name`` as seen from ``obj``, None when it cannot be told."""
    if name.startswith("."):
        module = obj.module
        base = module if module.is_init_module else module.parent
        return None if base is None else f"{base.path}.{name.lstrip('.')}"
    first, _, rest = name.partition(".")
    try:
        resolved = obj.resolve(first)
    except griffe.NameResolutionError:
        return name if name.startswith("pneumaquad.") else None
    return f"{resolved}.{rest}" if rest else resolved


def _link(obj: griffe.Object, match: re.Match[str]) -> str:
    name = " ".join(match["name"].split())
    target = re.sub(r"\s+", "", match["target"] or name)
    if not re.fullmatch(r"\.*[A-Za-z_][\w.]*", target):
        return match[0]
    shown = name.rsplit(".", 1)[-1] if match["tilde"] else name.lstrip(".")
    code = f"<code>{escape(shown)}{match['call'] or ''}</code>"
    identifier = _identifier(obj, target)
    if identifier is None:
        return code
    return f'<autoref identifier="{escape(identifier)}" optional>{code}</autoref>'


def _comment_doc(attr: griffe.Attribute) -> str | None:
    """The ``#:`` comment lines right above an attribute, joined; None without."""
    if not attr.lineno or isinstance(attr.filepath, list):
        return None
    try:
        lines = attr.lines_collection[attr.filepath]
    except KeyError:
        return None
    found: list[str] = []
    index = attr.lineno - 2
    while index >= 0 and lines[index].strip().startswith("#:"):
        found.insert(0, lines[index].strip()[2:].strip())
        index -= 1
    return "\n".join(found) or None


class SphinxRolesAndCommentDocs(griffe.Extension):
    """Links for Sphinx roles in docstrings; ``#:`` comments as attribute docstrings."""

    def on_attribute_instance(self, *, node: ast.AST | griffe.ObjectNode,
                              attr: griffe.Attribute, agent: Any, **kwargs: Any) -> None:
        """Give an attribute without a docstring the ``#:`` comment above it."""
        if attr.docstring is None and (text := _comment_doc(attr)):
            attr.docstring = griffe.Docstring(text, lineno=attr.lineno, parent=attr)

    def on_package(self, *, pkg: griffe.Module, loader: griffe.GriffeLoader,
                   **kwargs: Any) -> None:
        """Rewrite the roles of every docstring in the package, once it is loaded."""
        stack: list[griffe.Object] = [pkg]
        while stack:
            obj = stack.pop()
            if obj.docstring is not None and ":`" in obj.docstring.value:
                obj.docstring.value = _ROLE.sub(lambda m, o=obj: _link(o, m),
                                                obj.docstring.value)
            stack.extend(member for member in obj.members.values() if not member.is_alias)
