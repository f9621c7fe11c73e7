"""A run folder's files: satchain's (listed in its ``manifest.json``) and the user's, kept when a rerun replaces it.

A run is written into a staging folder beside ``-o`` and swapped in by two renames (:func:`swap_in`): the old
folder is renamed aside, the staging folder into its place, and the old one removed only then; a failure before
the second rename puts the old folder back. The files the old folder holds that satchain did not write (its
manifest's ``files`` does not list them: the user's notes, a drawing saved beside a figure) are hard-linked (or,
where the file system has no hard links, copied) into the staging folder before the swap, so they survive it
while their originals stay in place until the new folder is in: an interrupted or failed run changes nothing.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
from pathlib import Path

from satchain._safety import MARKER, OWNER, claim
from satchain.errors import SatchainIOError

__all__ = ["MANIFEST", "check_user_files", "swap_in", "written_files"]

#: The run folder's manifest: versions, seed, and ``files``, every file satchain wrote into the folder.
MANIFEST = "manifest.json"


def written_files(directory: str | os.PathLike) -> list[str]:
    """Every file of the run folder ``directory`` as satchain writes it (relative POSIX paths, sorted; the
    process's owner file left out): the manifest's ``files``. The manifest itself is listed."""
    d = Path(directory)
    files = {p.relative_to(d).as_posix() for p in d.rglob("*") if p.is_file() or p.is_symlink()}
    return sorted((files - {OWNER}) | {MANIFEST})


def _listed(out: Path) -> set[str] | None:
    """The files ``out``'s manifest lists as satchain's; None when it lists none (no manifest, or one written
    before manifests had the list)."""
    try:
        data = json.loads((out / MANIFEST).read_text())
        files = data.get("files")
    except (OSError, ValueError, AttributeError):
        return None
    if files is None and isinstance(data.get("cases"), list):  # a sweep's manifest from before it listed files
        files = [c.get(k) for c in data["cases"] if isinstance(c, dict) for k in ("image", "preview")]
        files += ["manifest.csv"]
    return {str(f) for f in files if f} if isinstance(files, list) else None


def _entries(out: Path) -> list[tuple[str, str]]:
    """``(relative path, "file" | "link" | "dir")`` of every file, symbolic link and empty folder under ``out``
    (links are not followed)."""
    found = []
    for root, dirs, files in os.walk(out):
        base = Path(root)
        for name in dirs + files:
            p = base / name
            rel = p.relative_to(out).as_posix()
            if p.is_symlink():
                found.append((rel, "link"))
            elif name in files:
                found.append((rel, "file"))
            elif not any(p.iterdir()):
                found.append((rel, "dir"))
    return sorted(found)


def _users(out: Path, new: set[str]) -> list[tuple[str, str]]:
    """The entries of the run folder ``out`` that satchain did not write, refusing one where the new run
    (whose files are ``new``) writes a file."""
    listed = _listed(out)
    new_dirs = set().union(*(_parents(f) for f in new))
    users = []
    for rel, what in _entries(out):
        if rel in (MARKER, OWNER, MANIFEST) or (rel in listed if listed is not None else rel in new):
            continue  # satchain's: replaced (without a list, a path this run writes again is taken as satchain's)
        if what == "dir" and rel in new_dirs:
            continue  # an empty folder the new run fills
        if rel in new or rel in new_dirs or _parents(rel) & new:
            raise SatchainIOError(
                f"-o {str(out)!r}: {rel!r} is not listed in its manifest.json (not written by satchain) and this "
                "run writes a file there; move it out of the folder and run again, nothing was changed"
            )
        users.append((rel, what))
    return users


def check_user_files(out: str | os.PathLike, new: set[str]) -> None:
    """Refuse, before any work, a run into ``out`` that would write one of the files ``new`` (relative paths)
    where ``out`` holds a file satchain did not write (see :func:`swap_in`)."""
    if Path(out).is_dir():
        _users(Path(out), set(new))


def _parents(rel: str) -> set[str]:
    """The folders above the relative path ``rel``: ``"a/b/c.txt"`` -> ``{"a", "a/b"}``."""
    parts = rel.split("/")
    return {"/".join(parts[:i]) for i in range(1, len(parts))}


def _carry(out: Path, staging: Path, users: list[tuple[str, str]]) -> None:
    """Put the user's entries into ``staging``: files hard-linked (copied where links cannot be made), links
    recreated, empty folders made. The originals are not touched."""
    for rel, what in users:
        src, dst = out / rel, staging / rel
        dst.parent.mkdir(parents=True, exist_ok=True)
        if what == "dir":
            dst.mkdir(exist_ok=True)
        elif what == "link":
            os.symlink(os.readlink(src), dst)
        else:
            try:
                os.link(src, dst)
            except OSError:
                shutil.copy2(src, dst)


def swap_in(staging: Path, out: Path) -> tuple[str, ...]:
    """Replace ``out`` by ``staging`` with two renames, keeping the files of ``out`` that satchain did not write
    (they are put into ``staging`` first); the old folder is removed only afterwards. Returns the relative paths
    of the user's entries kept (empty folders with a trailing ``/``).

    Raises
    ------
    SatchainIOError
        A file of the user's where this run writes one; nothing changed (the caller removes ``staging``).
    """
    old: Path | None = None
    kept: tuple[str, ...] = ()
    if out.exists():
        users = _users(out, set(written_files(staging)))
        _carry(out, staging, users)
        kept = tuple(rel + "/" if what == "dir" else rel for rel, what in users)
        old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
        os.rmdir(old)
        claim(out)  # owned by this process from before it is renamed
        os.replace(out, old)
    try:
        os.replace(staging, out)
    except BaseException:
        if old is not None:
            os.replace(old, out)
            with contextlib.suppress(OSError):
                (out / OWNER).unlink()
        raise
    with contextlib.suppress(OSError):
        (out / OWNER).unlink()  # the results no longer belong to a process
    if old is not None:
        with contextlib.suppress(OSError):
            shutil.rmtree(old)
    return kept
