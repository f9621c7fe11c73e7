"""Retiring public names with a versioned warning: a renamed result field stays readable, under its old name,
for one minor version, and says so (:class:`satchain.errors.SatchainDeprecationWarning`)."""

from __future__ import annotations

import warnings

from satchain.errors import SatchainDeprecationWarning

__all__ = ["DEPRECATED_IN", "REMOVED_IN", "warn_renamed"]

#: The version that deprecates the names retired now, and the one that removes them.
DEPRECATED_IN, REMOVED_IN = "0.1", "0.2"


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
