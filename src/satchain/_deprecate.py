"""Retiring public names with a versioned warning: a renamed result field stays readable, under its old name,
for one minor version, and says so (:class:`satchain.errors.SatchainDeprecationWarning`); a renamed JSON key is
written beside its new name, with the same value, for as long (:func:`with_renamed_keys`). CHANGELOG.md lists
every name here with its replacement (tests/test_changelog_aliases.py keeps the two in agreement)."""

from __future__ import annotations

import warnings
from typing import Any

from satchain.errors import SatchainDeprecationWarning

__all__ = ["DEPRECATED_IN", "RENAMED", "renamed_json_keys", "REMOVED_IN", "warn_renamed", "with_renamed_keys"]

#: The version that deprecates the names retired now, and the one that removes them.
DEPRECATED_IN, REMOVED_IN = "0.1", "0.2"

#: Every public name renamed and still accepted under its former one until :data:`REMOVED_IN`, with a warning:
#: (owner, old name, new name); the owner is a result type (an attribute) or a function (a keyword argument).
RENAMED: tuple[tuple[str, str, str], ...] = (
    ("EdgeResult", "edge_angle_deg", "angle_deg"),
    ("EdgeResult", "mtf_at_nyquist_std", "mtf_at_nyquist_sigma"),
    ("measure_edge", "saturation_level", "full_scale"),
    ("SceneResult", "typed_truth", "truth"),
)


def renamed_json_keys() -> dict[str, dict[str, dict[str, str]]]:
    """JSON keys renamed in an output, written beside their new name with its value until :data:`REMOVED_IN`:
    {output: {where: {old key: new key}}}. The output is the JSON file's stem (``measure edge`` writes edge.json,
    ``measure auto`` auto.json, their ``--json`` prints the same); where is ``""`` for the top level, else the key
    of a list whose every item carries the key (auto.json's slanted edges, named by the measure layer's registry,
    imported here when first asked for: the measurement modules import this one)."""
    from satchain.measure._keys import RESULT_KEY
    from satchain.scene.targets import SlantedEdge

    return {
        "edge": {"": {"edge_angle_deg": "angle_deg", "mtf_at_nyquist_std": "mtf_at_nyquist_sigma"}},
        "auto": {RESULT_KEY[SlantedEdge.kind]: {"mtf_at_nyquist_std": "mtf_at_nyquist_sigma"}},
    }


def warn_renamed(owner: str, old: str, new: str, *, stacklevel: int = 3) -> None:
    """Warn that ``owner.old`` is deprecated in favour of ``owner.new``, naming the versions.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as w:
    ...     warnings.simplefilter("always")
    ...     warn_renamed("Result", "old", "new")
    >>> print(w[0].message)
    Result.old is deprecated in satchain 0.1 and will be removed in 0.2: use Result.new
    """
    warnings.warn(
        f"{owner}.{old} is deprecated in satchain {DEPRECATED_IN} and will be removed in {REMOVED_IN}: "
        f"use {owner}.{new}",
        SatchainDeprecationWarning,
        stacklevel=stacklevel,
    )


def _beside(d: dict, renamed: dict[str, str]) -> dict:
    """``d`` with each old key right after its new one (same value), where the new one is there and the old not."""
    out: dict[str, Any] = {}
    for key, value in d.items():
        out[key] = value
        for old, new in renamed.items():
            if key == new and old not in d:
                out[old] = value
    return out


def with_renamed_keys(output: str, payload: dict) -> dict:
    """The JSON ``payload`` of ``output`` with every renamed key of :func:`renamed_json_keys` beside its new
    name (a new dict; ``payload`` is left as it is).

    Examples
    --------
    >>> with_renamed_keys("edge", {"angle_deg": 5.0, "mtf_at_nyquist_sigma": 0.01})
    {'angle_deg': 5.0, 'edge_angle_deg': 5.0, 'mtf_at_nyquist_sigma': 0.01, 'mtf_at_nyquist_std': 0.01}
    >>> with_renamed_keys("find", {"angle_deg": 5.0})
    {'angle_deg': 5.0}
    """
    out = dict(payload)
    for where, renamed in renamed_json_keys().get(output, {}).items():
        if where == "":
            out = _beside(out, renamed)
        elif isinstance(out.get(where), list):
            out[where] = [_beside(it, renamed) if isinstance(it, dict) else it for it in out[where]]
    return out
