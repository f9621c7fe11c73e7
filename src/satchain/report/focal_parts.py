"""The content of one "focal plane as flown" report part (:mod:`satchain.report.focal_plane`)."""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["FocalParts", "FocalTable"]


@dataclass(frozen=True)
class FocalTable:
    """A table of the section: ``columns`` (headers; the first is left-aligned), ``rows`` (cells as text)."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    note: str = ""


@dataclass(frozen=True)
class FocalParts:
    """One section's content: ``key`` (anchor), ``title``, ``text`` (a paragraph), ``tables``, ``figures``
    (``(file name in fig_dir, caption)``)."""

    key: str
    title: str
    text: str = ""
    tables: tuple[FocalTable, ...] = ()
    figures: tuple[tuple[str, str], ...] = field(default_factory=tuple)
