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
from pathlib import Path

from pedenv.errors import InputError

#: The file pedenv leaves in every output folder it prepares; ``overwrite`` needs it.
MARKER = ".pedenv-output"


def prepare_output_dir(path: str | Path, *, overwrite: bool = False, command: str = "pedenv") -> Path:
    """Create ``path`` as an empty folder for one run of ``command`` and return it.

    Raises InputError if ``path`` is a file, lies under a file, is not writable, or is a
    non-empty folder and ``overwrite`` is off (or it is on but pedenv did not write the folder).
    """
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(f"output folder {path} is an existing file; choose a folder")
    blocking = next((p for p in path.parents if p.exists() and not p.is_dir()), None)
    if blocking is not None:
        raise InputError(f"output folder {path} lies under {blocking}, which is a file")
    if path.is_dir() and any(path.iterdir()):
        if not overwrite:
            raise InputError(f"output folder {path} is not empty; pass --overwrite to replace what an earlier run "
                             f"wrote there, or choose another folder")
        if not (path / MARKER).is_file():
            raise InputError(
                f"output folder {path} is not empty and was not written by pedenv (no {MARKER} file); "
                f"--overwrite only replaces pedenv's own output folders: empty it or choose another folder"
            )
        _clear(path)
    try:
        path.mkdir(parents=True, exist_ok=True)
        (path / MARKER).write_text(f"written by {command}; --overwrite may delete this folder's contents\n")
    except OSError as exc:
        raise InputError(f"output folder {path} cannot be written: {exc.strerror or exc}") from None
    return path


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


def writable_file(path: str | Path, what: str = "output file") -> Path:
    """``path`` with its folder created, checked to be no folder; InputError naming it otherwise."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{what} {path} is a folder")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create the folder of {what} {path}: {exc.strerror or exc}") from None
    return path
