"""A griffe extension (mkdocstrings' python handler, ``extensions:`` in mkdocs.yml) that turns the reST roles of
satchain's numpydoc docstrings (``:func:`x```, ``:class:`~a.b.C```, ``:mod:``, ``:meth:``, ``:attr:``, ``:data:``)
into cross-references: a link to the object's entry in the API reference where it has one, its name in code
otherwise (an *optional* autoref, so a name outside the reference never warns)."""

from __future__ import annotations

import html
import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?(?:func|class|mod|meth|attr|data|exc|obj|const):`(?P<target>[^`]+)`")


def _resolve(obj: griffe.Object, pkg: griffe.Module, name: str) -> str | None:
    """The full dotted path ``name`` stands for in ``obj``'s scope (its members, its module's imports, up the
    parents), the canonical path of what an import names; None when it cannot be found."""
    try:
        if "." in name and name.split(".", 1)[0] == pkg.name:
            path = name
        else:
            head, _, rest = name.partition(".")
            path = obj.resolve(head) + (f".{rest}" if rest else "")
    except Exception:  # noqa: BLE001  (an unknown name stays plain code)
        return None
    try:
        target = pkg.modules_collection[path]
        return str(target.canonical_path)
    except Exception:  # noqa: BLE001  (an alias to something not loaded: the path as written)
        return path


_PARAM_LINE = re.compile(r"^\s*\*{0,2}[A-Za-z_][\w, *]*\s:\s")  # "name : type" of a numpydoc section
_UNDERLINE = re.compile(r"^\s*(-{3,}|={3,})\s*$")  # a section title's underline


def _rewrite(text: str, obj: griffe.Object, pkg: griffe.Module) -> str:
    def one(m: re.Match[str], *, plain: bool) -> str:
        raw = m.group("target").strip()
        label_override = None
        explicit = re.fullmatch(r"(?P<label>.+?)\s*<(?P<target>[^>]+)>", raw)  # :func:`label <target>`
        if explicit:
            label_override, raw = explicit.group("label"), explicit.group("target")
        short = raw.startswith("~")
        name = raw.lstrip("~").lstrip(".").removesuffix("()")
        label = label_override or (name.rsplit(".", 1)[-1] if short else name)
        if plain:  # a parameter's type or a section title: rendered as text, no markup
            return label
        code = f"<code>{html.escape(label)}</code>"
        path = _resolve(obj, pkg, name)
        if path is None:
            return code
        return f'<autoref identifier="{html.escape(path)}" optional>{code}</autoref>'

    lines = text.split("\n")
    for i, line in enumerate(lines):
        if ":" not in line:
            continue
        title = i + 1 < len(lines) and bool(_UNDERLINE.match(lines[i + 1]))
        plain = title or bool(_PARAM_LINE.match(line))
        lines[i] = _ROLE.sub(lambda m, plain=plain: one(m, plain=plain), line)
    return "\n".join(lines)


class RstRoles(griffe.Extension):
    """Rewrite reST roles in every docstring of a loaded package into optional autorefs."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        seen: set[int] = set()

        def walk(obj: griffe.Object) -> None:
            if id(obj) in seen:
                return
            seen.add(id(obj))
            if obj.docstring is not None and ":" in obj.docstring.value:
                obj.docstring.value = _rewrite(obj.docstring.value, obj, pkg)
            for member in obj.members.values():
                if not member.is_alias:
                    walk(member)  # type: ignore[arg-type]

        walk(pkg)
