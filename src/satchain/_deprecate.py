"""Retiring public names with a versioned warning: a renamed result field stays readable, under its old name,
for one minor version, and says so (:class:`satchain.errors.SatchainDeprecationWarning`); a renamed JSON key is
written beside its new name, with the same value, for as long, where the JSON is written
(:func:`satchain.cli.output.with_renamed_keys`, which names the outputs' renamed keys). CHANGELOG.md lists every
name here and there with its replacement (tests/test_changelog_aliases.py keeps them in agreement)."""

from __future__ import annotations

import warnings

from satchain.errors import SatchainDeprecationWarning

__all__ = ["DEPRECATED_IN", "RENAMED", "REMOVED_IN", "warn_renamed"]

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
