"""The validating base of the system sections (:mod:`satchain.config.sections`, :mod:`satchain.config.sections_motion`):
frozen pydantic models that refuse booleans, strings and NaN where a number is wanted, and turn pydantic's report
into one :class:`~satchain.errors.ConfigError` line naming key, value and allowed range."""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import Any, ClassVar, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, ValidationError, field_validator

from satchain.errors import ConfigError

__all__: list[str] = []

#: A model validator's message that starts with the name of one of its fields ("qe[1] = 1.2: ...").
_NAMES_A_FIELD = re.compile(r"[a-z_][a-z0-9_]*(\[\d+\])? (=|has) ")


def schema_bounds(
    *, number: dict[str, float] | None = None, items: dict[str, float] | None = None
) -> Callable[[dict[str, Any]], None]:
    """A ``json_schema_extra`` that writes bounds a validator enforces into a field's JSON Schema (validation and
    its messages are unchanged): ``number`` on a plain number (``qe = 0.8``), ``items`` on every element of an
    array (``wavelengths_m``, ``band_m``) or value of a table (``zernike_rms_waves``), in each alternative of an
    ``anyOf`` (``float | tuple[float, ...] | None``).

    Examples
    --------
    >>> s = {"anyOf": [{"type": "array", "items": {"type": "number"}}, {"type": "null"}]}
    >>> schema_bounds(items={"minimum": 0})(s); s["anyOf"][0]["items"]
    {'type': 'number', 'minimum': 0}
    """

    def extra(s: dict[str, Any]) -> None:
        for alt in (s, *s.get("anyOf", ())):
            kind = alt.get("type")
            if kind == "number" and number:
                alt.update(number)
            elif kind == "array" and items:
                for element in (alt.get("items"), *alt.get("prefixItems", ())):
                    if isinstance(element, dict):
                        element.update(items)
            elif kind == "object" and items and isinstance(alt.get("additionalProperties"), dict):
                alt["additionalProperties"].update(items)

    return extra


def _number_kinds(annotation: Any) -> tuple[bool, bool]:
    """(takes a number, takes a bool or a string) for a field annotation, looking through unions and
    containers: ``float | None`` -> (True, False); ``tuple[float, ...]`` -> (True, False); ``bool`` ->
    (False, True)."""
    if annotation in (float, int):
        return True, False
    if annotation in (bool, str, Any) or getattr(annotation, "__origin__", None) is Literal:
        return False, True
    args = [a for a in getattr(annotation, "__args__", ()) if a is not type(None) and a is not Ellipsis]
    if getattr(annotation, "__origin__", None) is dict:
        args = args[1:]  # the values (TOML keys are always strings)
    kinds = [_number_kinds(a) for a in args]
    return any(k[0] for k in kinds), any(k[1] for k in kinds)


_BOUNDS = (("gt", True, True), ("ge", True, False), ("lt", False, True), ("le", False, False))


def _allowed(field: Any) -> str:
    """The interval a field's constraints allow, e.g. ``" in (0, 1e+08]"``, or ``""``."""
    lo = hi = None
    lo_open = hi_open = False
    for m in getattr(field, "metadata", ()):
        for attr, is_lo, is_open in _BOUNDS:
            v = getattr(m, attr, None)
            if v is not None:
                lo, lo_open = (v, is_open) if is_lo else (lo, lo_open)
                hi, hi_open = (v, is_open) if not is_lo else (hi, hi_open)
    if lo is None and hi is None:
        return ""
    left, right = ("(" if lo_open or lo is None else "["), (")" if hi_open or hi is None else "]")
    return f" in {left}{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}{right}"


def _not_a_number(value: Any, allowed: str = "") -> str | None:
    """Why ``value`` cannot stand for a number (a bool, a string, NaN/inf), or None when it can."""
    if isinstance(value, (bool, np.bool_)):
        return f"must be a number{allowed}, not the boolean {str(bool(value)).lower()}"
    if isinstance(value, (str, bytes)):
        return f"must be a number{allowed}, not a string (write it without quotes)"
    if isinstance(value, (float, np.floating)) and not math.isfinite(value):
        return f"not a finite number; must be a finite number{allowed}"
    return None


def _config_error(exc: ValidationError, title: str = "invalid imaging system") -> ConfigError:
    """Turn pydantic's report into one ConfigError naming key, value and allowed range."""
    lines = []
    for e in exc.errors():
        loc = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in e["loc"]).lstrip(".")
        msg = e["msg"].removeprefix("Value error, ")
        if e["type"] == "extra_forbidden":
            lines.append(f"{loc}: unknown key (check the spelling; allowed keys are listed in the docs)")
        elif e["type"] == "missing":
            lines.append(f"{loc}: required key is missing")
        elif loc and "input" in e and not isinstance(e["input"], dict) and not msg.startswith(loc):
            lines.append(f"{loc} = {e['input']!r}: {msg[0].lower() + msg[1:]}")
        elif loc and _NAMES_A_FIELD.match(msg):  # "frequency_hz = [...]: ..." of a table at loc
            lines.append(f"{loc}.{msg}")
        else:
            lines.append(f"{loc + ': ' if loc and not msg.startswith(loc) else ''}{msg}")
    return ConfigError(f"{title}: " + "; ".join(lines))


def _model_of(annotation: Any) -> type[BaseModel] | None:
    """The section model a field holds (``Spiders | None``, ``tuple[Oscillation, ...]``), or None."""
    if isinstance(annotation, type) and issubclass(annotation, _StrictNumbers):
        return annotation
    for arg in getattr(annotation, "__args__", ()):
        model = _model_of(arg)
        if model is not None:
            return model
    return None


def _unknown_key_lines(model: type[BaseModel], data: Any, loc: str = "") -> list[str]:
    """One line per key of ``data`` (nested sections and arrays of tables included) that ``model`` does not
    take, naming the closest valid key (difflib) or listing the allowed ones."""
    import difflib

    if not isinstance(data, dict):
        return []
    known = [*model.model_fields, *getattr(model, "_input_keys", ())]
    lines = []
    for key, value in data.items():
        where = f"{loc}.{key}" if loc else str(key)
        if key not in known:
            close = difflib.get_close_matches(str(key), known, n=1, cutoff=0.6)
            hint = f"did you mean {close[0]}?" if close else f"allowed: {', '.join(known)}"
            lines.append(f"{where}: unknown key; {hint}")
            continue
        sub = _model_of(model.model_fields[key].annotation) if key in model.model_fields else None
        if sub is None:
            continue
        if isinstance(value, (list, tuple)):
            for i, item in enumerate(value):
                lines += _unknown_key_lines(sub, item, f"{where}[{i}]")
        else:
            lines += _unknown_key_lines(sub, value, where)
    return lines


def refuse_unknown_keys(model: type[BaseModel], data: Any, title: str) -> None:
    """Refuse misspelt or unknown keys before any validation, so that the missing-key and consistency errors
    that follow from a misspelling ("optics.f_number: required key is missing") do not hide it."""
    lines = _unknown_key_lines(model, data)
    if lines:
        raise ConfigError(f"{title}: " + "; ".join(lines))


class _StrictNumbers(BaseModel):
    """Refuses a bool (``true`` taken as 1), a string (``"0.035"``) or NaN/inf where a number is wanted, in
    every field and in the items of tuple and dict fields, and anything but true/false for a flag, with a
    message naming the value and what is allowed."""

    #: the start of the one-line error of a direct construction, e.g. ``ImagingSystem(orbit=5)``
    _error_title: ClassVar[str] = ""

    #: keys a ``mode="before"`` validator takes besides the fields (``detector.pitch_m``, ``fill_factor``)
    _input_keys: ClassVar[tuple[str, ...]] = ()

    def __init__(self, /, **data: Any) -> None:
        refuse_unknown_keys(type(self), data, self._error_title or f"invalid {type(self).__name__}")
        try:
            super().__init__(**data)
        except ValidationError as exc:
            raise _config_error(exc, self._error_title or f"invalid {type(self).__name__}") from None

    __init__.__pydantic_base_init__ = True  # type: ignore[attr-defined]  # validation itself never calls it

    @field_validator("*", mode="before")
    @classmethod
    def _strict_numbers(cls, value: Any, info) -> Any:
        field = cls.model_fields[info.field_name]
        if field.annotation is bool:
            if not isinstance(value, (bool, np.bool_)):
                raise ValueError("must be true or false")
            return value
        numeric, other = _number_kinds(field.annotation)
        if not numeric or other:
            return value
        several = isinstance(value, (list, tuple, dict))
        items = list(value.values() if isinstance(value, dict) else value) if several else [value]
        for item in items:
            why = _not_a_number(item, "" if several else _allowed(field))
            if why is not None:
                raise ValueError(f"{why} (the entry {item!r})" if several else why)
        return value


class _Frozen(_StrictNumbers):
    model_config = ConfigDict(frozen=True, extra="forbid", validate_default=True)
