"""Output folders: one run per folder, and a clear error when a folder cannot take it.

Every command that writes a folder (``run``, ``evaluate``, ``simulate``, ``detect``,
``demo``) prepares it with :func:`prepare_output_dir` after its inputs are checked:

* a path that is a file, lies under a file or cannot be written is refused with one
  :class:`~pedenv.errors.InputError` naming it;
* a folder that is not empty is refused unless ``overwrite`` is given, so two runs never
  mix in one folder (stale overlays of a longer run, an earlier ``environment.jsonl``);
* with ``overwrite`` the folder's contents are deleted first, but only in a folder pedenv
  wrote itself (it holds the marker file :data:`MARKER`), so a mistyped ``--output ~``
  never deletes anything of the user's.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from pedenv.errors import InputError
from pedenv.paths import MARKER, check_path, is_utf8, writable_file

__all__ = ["MARKER", "check_output_file", "glob_escape", "holds_files", "prepare_output_dir", "refuse_output_dir",
           "writable_file"]


def prepare_output_dir(path: str | Path, *, overwrite: bool = False, command: str = "pedenv") -> Path:
    """Create ``path`` as an empty folder for one run of ``command`` and return it.

    Raises InputError if ``path`` is a file, lies under a file, is not writable, or is a
    non-empty folder and ``overwrite`` is off (or it is on but pedenv did not write the folder).
    """
    path = refuse_output_dir(path, overwrite=overwrite)
    if holds_files(path):
        _clear(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
        (path / MARKER).write_text(f"written by {command}; --overwrite may delete this folder's contents\n")
    except OSError as exc:
        raise InputError(f"output folder {path} cannot be written: {exc.strerror or exc}") from None
    return path


def refuse_output_dir(path: str | Path, *, overwrite: bool = False) -> Path:
    """``path`` as :func:`prepare_output_dir` takes it, without touching it. Raises InputError if it is
    a file, lies under a file, or is a non-empty folder and ``overwrite`` is off (or it is on but
    pedenv did not write the folder)."""
    path = check_path(path, "output folder")
    if path.exists() and not path.is_dir():
        raise InputError(f"output folder {path} is an existing file; choose a folder")
    blocking = next((p for p in path.parents if p.exists() and not p.is_dir()), None)
    if blocking is not None:
        raise InputError(f"output folder {path} lies under {blocking}, which is a file")
    if holds_files(path):
        if not overwrite:
            raise InputError(f"output folder {path} is not empty; pass --overwrite to replace what an earlier run "
                             f"wrote there, or choose another folder")
        if not (path / MARKER).is_file():
            raise InputError(
                f"output folder {path} is not empty and was not written by pedenv (no {MARKER} file); "
                f"--overwrite only replaces pedenv's own output folders: empty it or choose another folder"
            )
    return path


def holds_files(path: Path) -> bool:
    """Whether ``path`` is a folder with something in it (an earlier run, or anything else)."""
    return path.is_dir() and any(path.iterdir())


def _clear(path: Path) -> None:
    try:
        for child in path.iterdir():
            if child.is_dir() and not child.is_symlink():
                shutil.rmtree(child)
            else:
                child.unlink()
    except OSError as exc:
        raise InputError(f"output folder {path}: cannot delete the earlier run's {exc.filename}: "
                         f"{exc.strerror or exc}") from None



def check_output_file(path: str | Path, flag: str, suffix: str, *, overwrite: bool = False) -> Path:
    """Check a file a run is asked to write (``--rerun FILE.rrd``, ``--mcap FILE.mcap``) before it starts.

    Refused with one InputError naming ``flag`` and the path: a name without ``suffix`` (so
    that no input, such as the poses CSV, and no file the run writes itself, such as
    ``environment.jsonl``, is ever written over), a name that is not UTF-8 (the Rerun and
    MCAP libraries cannot take it), a folder, a path under a file, a folder
    that cannot be written, and an existing file (or, for several scenes, an existing
    ``<stem>-<scene><suffix>``) unless ``overwrite``. Nothing is created (the writer makes
    the missing folders when the run starts).
    """
    path = check_path(path, flag)
    if not is_utf8(path):
        raise InputError(f"{flag} {path}: the name is not UTF-8 text, which the {flag[2:]} writer needs; "
                         f"choose another name")
    if path.suffix.lower() != suffix:
        raise InputError(f"{flag} {path}: the file name must end in {suffix} (pedenv writes no file of another kind "
                         f"there, so that no input or other output is written over)")
    if path.is_dir():
        raise InputError(f"{flag} {path} is a folder; give a file name ending in {suffix}")
    blocking = next((p for p in path.parents if p.exists() and not p.is_dir()), None)
    if blocking is not None:
        raise InputError(f"{flag} {path} lies under {blocking}, which is a file")
    earlier = [path] if path.exists() else sorted(path.parent.glob(f"{glob_escape(path.stem)}-*{suffix}"))
    if earlier and not overwrite:
        raise InputError(f"{flag} {earlier[0]} exists; pass --overwrite to replace it, or choose another name")
    existing = next(p for p in (path.parent, *path.parent.parents) if p.exists())
    try:  # nothing is created before the run: the nearest existing folder must take a file
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as exc:
        raise InputError(f"{flag} {path} cannot be written: {exc.strerror or exc}") from None
    return path


def glob_escape(name: str) -> str:
    """``name`` with the glob pattern characters ``*?[`` taken literally."""
    return "".join(f"[{c}]" if c in "*?[" else c for c in name)
