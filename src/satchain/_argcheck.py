"""Type checks at the public entry points: a wrong type is refused with one line naming the function, the
parameter, the value and what is allowed, as a :class:`~satchain.errors.ParameterTypeError` (a ``SatchainError``
that is also a ``TypeError`` and a ``ValueError``), before any work.

:func:`checked` wraps a function; its rules come from the parameter's annotation (``float``, ``int | None``,
``bool``, ``str``) and from the project's one vocabulary of parameter names (``image``, ``truth``, ``system``,
``progress``, ``center``, ``origin_m``, ``periods_px``, ...). Values (ranges, shapes, NaN) are checked by the
functions themselves (:mod:`satchain._validate`), which name the allowed range.

Examples
--------
>>> @checked
... def area(width_m: float, *, scale: int = 1) -> float:
...     return width_m * scale
>>> area(2.0, scale=3)
6.0
>>> try:
...     area("2.0")
... except TypeError as exc:
...     print(exc)
area(): width_m = '2.0': must be a number, not a string
"""

from __future__ import annotations

import functools
import inspect
import numbers
import os
from collections.abc import Callable, Mapping
from typing import Any, TypeVar

import numpy as np

from satchain.errors import ParameterTypeError

__all__ = ["checked", "check_argument"]

F = TypeVar("F", bound=Callable[..., Any])

_NUMBER_TYPES = {"float", "int"}
#: annotation names checked by isinstance (paths, mappings) and the project's classes that appear beside them
_TYPES = {"str": (str,), "Path": (str, os.PathLike), "Mapping": (Mapping,), "dict": (dict,)}
#: spellings of a path annotation, checked (and named in messages) as ``Path``
_PATH_ALIASES = {"os.PathLike": "Path", "PathLike": "Path"}
_CLASSES = {"Truth", "RunConfig", "ImagingSystem", "Predictions"}


def _parts(annotation: Any) -> set[str]:
    """Top-level alternatives of an annotation string: ``"float | None"`` -> ``{"float", "None"}``."""
    if annotation is inspect.Parameter.empty:
        return set()
    text = annotation if isinstance(annotation, str) else getattr(annotation, "__name__", str(annotation))
    parts, depth, cur = set(), 0, ""
    for ch in text:
        depth += ch in "[("
        depth -= ch in "])"
        if ch == "|" and depth == 0:
            parts.add(cur.strip())
            cur = ""
        else:
            cur += ch
    parts.add(cur.strip())
    bare = (p.split("[", 1)[0] for p in parts if p)
    return {_PATH_ALIASES.get(p, p) for p in bare}


def _kind(value: Any) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "a boolean"
    if isinstance(value, (str, bytes)):
        return "a string"
    name = type(value).__name__
    return f"{'an' if name[0] in 'aeiouAEIOU' else 'a'} {name}"


def _is_number(value: Any) -> bool:
    return isinstance(value, (numbers.Real, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _numbers(value: Any, n: int | None = None) -> bool:
    """A sequence (or array) of real numbers, of length ``n`` when given."""
    if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__"):
        return False
    try:
        items = list(np.asarray(value, dtype=object).ravel())
    except (TypeError, ValueError):
        return False
    return (n is None or len(items) == n) and all(_is_number(v) for v in items)


def _is_instance(value: Any, parts: set[str]) -> bool:
    types = tuple(t for p in parts for t in _TYPES.get(p, ()))
    return isinstance(value, types) or any(c.__name__ in parts for c in type(value).__mro__)


def _by_name(name: str, value: Any) -> str | None:
    """What the project's parameter name requires, when ``value`` does not fit it (else None)."""
    from satchain._validate import _check_array_like
    from satchain.errors import InputError

    if name in ("image", "ground_truth") and not hasattr(value, "render") and not hasattr(value, "read"):
        try:
            _check_array_like(name, value)
        except InputError as exc:
            return str(exc).split(": ", 1)[1]
    elif name == "truth" and not isinstance(value, Mapping) and not hasattr(value, "to_dict"):
        return "must be a scene truth record (a dict, or satchain.read_truth(path) for a .truth.json file)"
    elif name == "system":
        # by the class's home, not by importing it: config.system (a layer above) decorates with @checked
        home = ("satchain.config.system", "ImagingSystem")
        if not any((c.__module__, c.__qualname__) == home for c in type(value).__mro__):
            return "must be an ImagingSystem (satchain.load_system(path) or satchain.load_preset(name))"
    elif name == "progress" and value is not None and not callable(value):
        return "must be a function progress(...) or None"
    elif name in ("center", "origin_m") and value is not None and not _numbers(value, 2):
        return "must be two numbers (x, y) or None"
    elif name == "periods_px" and not _numbers(value):
        return "must be a sequence of numbers (periods in pixels)"
    elif name in ("out_dir", "path_or_preset") and not isinstance(value, (str, os.PathLike)):
        return "must be a path (str or pathlib.Path)" + (" or None" if name == "out_dir" else "")
    return None


def check_argument(function: str, name: str, value: Any, annotation: Any = inspect.Parameter.empty) -> None:
    """Raise ParameterTypeError when ``value`` does not fit the parameter ``name`` of ``function``."""
    if value is None and name in ("out_dir",):
        return
    why = _by_name(name, value)
    parts = _parts(annotation)
    if why is None and parts and "Any" not in parts:
        optional = "None" in parts
        if value is None:
            why = None if optional else "must be given (not None)"
        elif parts - {"None"} <= _NUMBER_TYPES:
            if not _is_number(value):
                what = "an integer" if parts - {"None"} == {"int"} else "a number"
                why = f"must be {what}{' or None' if optional else ''}, not {_kind(value)}"
            elif parts - {"None"} == {"int"} and not float(value).is_integer():
                why = f"must be an integer{' or None' if optional else ''}"
        elif parts - {"None"} == {"bool"} and not isinstance(value, (bool, np.bool_)):
            why = f"must be True or False, not {_kind(value)}"
        elif parts - {"None"} == {"str"} and not isinstance(value, str):
            why = f"must be a string, not {_kind(value)}"
        elif "bool" not in parts and isinstance(value, (bool, np.bool_)) and parts & _NUMBER_TYPES:
            why = "must not be a boolean"
        elif parts - {"None"} <= set(_TYPES) | _CLASSES and not _is_instance(value, parts):
            allowed = " or ".join(sorted(parts - {"None"}))
            why = f"must be {allowed}{' or None' if optional else ''}, not {_kind(value)}"
    if why is not None:
        shown = repr(value) if not isinstance(value, np.ndarray) else f"array of shape {value.shape}"
        shown = shown if len(shown) <= 60 else shown[:57] + "..."
        raise ParameterTypeError(f"{function}(): {name} = {shown}: {why}")


def checked(fn: F) -> F:
    """Wrap ``fn`` so that its arguments are checked (:func:`check_argument`) before it runs; a missing or
    unknown argument is a ParameterTypeError too."""
    if getattr(fn, "__satchain_checked__", False):
        return fn
    sig = inspect.signature(fn)

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            bound = sig.bind(*args, **kwargs)
        except TypeError as exc:
            raise ParameterTypeError(f"{fn.__name__}(): {exc}") from None
        for name, value in bound.arguments.items():
            param = sig.parameters[name]
            if param.kind not in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
                check_argument(fn.__name__, name, value, param.annotation)
        return fn(*args, **kwargs)

    wrapper.__dict__["__satchain_checked__"] = True  # the marker getattr() reads above
    return wrapper  # type: ignore[return-value]
