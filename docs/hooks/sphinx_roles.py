"""A griffe extension for the API reference: the docstrings' Sphinx roles as code.

The numpy-style docstrings name other objects the Sphinx way (``:func:`upm.transition```,
``:data:`~eval.metrics.METRICS```), which mkdocstrings would print as they are. Here each
role becomes inline code of its target (``~`` keeps the last component, an explicit title
``:func:`title <target>``` keeps the title), before the docstring is parsed. Loaded by
mkdocs.yml (``plugins: mkdocstrings: ... extensions``); not part of the package.
"""

from __future__ import annotations

import re

import griffe

#: ``:role:`target``` or ``:py:role:`target```, the role being one of Sphinx's Python ones.
ROLE = re.compile(r":(?:py:)?(?:mod|func|class|meth|data|attr|exc|obj|const|term):`([^`]+)`")


def _code(match: re.Match) -> str:
    text = match.group(1).strip()
    titled = re.fullmatch(r"(.+?)\s*<(.+)>", text)
    if titled:
        return f"`{titled.group(1)}`"
    if text.startswith("~"):
        text = text[1:].rsplit(".", 1)[-1]
    return f"`{text}`"


def plain_roles(text: str) -> str:
    """``text`` with every Sphinx role written as inline code."""
    return ROLE.sub(_code, text)


class SphinxRoles(griffe.Extension):
    """Rewrite the roles of every docstring griffe loads."""

    def on_object(self, *, obj: griffe.Object, **kwargs) -> None:
        if obj.docstring is not None:
            obj.docstring.value = plain_roles(obj.docstring.value)

    def on_package(self, *, pkg: griffe.Module, **kwargs) -> None:
        """The top-level package itself (``on_object`` sees the objects under it)."""
        self.on_object(obj=pkg)
