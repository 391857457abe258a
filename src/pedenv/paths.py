"""File names the OS and OpenCV can take: a clear error for a name too long, and a way to
hand OpenCV a file whose name is not UTF-8.

* :func:`check_path` refuses a path with a component longer than :data:`MAX_NAME_BYTES`
  (``OSError: File name too long`` otherwise, from the first ``exists()``), naming it.
* :func:`opencv_path` gives OpenCV a name it can take. OpenCV converts a Python name to
  UTF-8 text and crashes the process (a segfault) on a name with a non-UTF-8 byte
  (``x\\xff.png``, ``str`` with a surrogate escape); such a file is reached through a
  symbolic link with a plain name in a fresh temporary folder instead.
* :func:`writable_file` and :data:`MARKER`: an output file's folder made, and the marker of
  pedenv's own output folders (here, below the readers and the writers alike).
"""

from __future__ import annotations

import os
import shutil
import stat
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from pedenv.errors import InputError

#: The file pedenv leaves in every output folder it prepares; ``--overwrite`` needs it
#: (:func:`pedenv.outputs.output_dir.prepare_output_dir`).
MARKER = ".pedenv-output"
#: Longest file or folder name (one path component) in bytes: Linux's and macOS's NAME_MAX.
MAX_NAME_BYTES = 255


def check_path(path: str | Path, what: str) -> Path:
    """``path`` as a Path; InputError naming ``what`` when one of its names is longer than
    :data:`MAX_NAME_BYTES` bytes (the file system would refuse it)."""
    path = Path(path)
    for part in path.parts:
        size = len(os.fsencode(part))
        if size > MAX_NAME_BYTES:
            raise InputError(f"{what} {_short(path)}: the name {_short(part)} is {size} bytes long; file systems take "
                             f"at most {MAX_NAME_BYTES}")
    return path


def writable_file(path: str | Path, what: str = "output file") -> Path:
    """``path`` with its folder created, checked to be no folder; InputError naming it otherwise."""
    path = check_path(path, what)
    if path.is_dir():
        raise InputError(f"{what} {path} is a folder")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create the folder of {what} {path}: {exc.strerror or exc}") from None
    return path


def refuse_special_file(path: str | Path, what: str) -> Path:
    """``path``; InputError when it exists and is no regular file (a FIFO or a device would block
    or never end a read; a folder is no ``what``)."""
    path = check_path(path, what)
    try:
        mode = path.stat().st_mode
    except OSError:
        return path  # missing: the reader names it
    if not stat.S_ISREG(mode):
        raise InputError(f"{what} {path} is not a regular file (a FIFO, a device or a folder); give a file")
    return path


def is_utf8(path: str | Path) -> bool:
    """Whether the bytes of ``path`` are UTF-8 text (what OpenCV needs)."""
    try:
        os.fsencode(path).decode("utf-8")
    except UnicodeDecodeError:
        return False
    return True


@contextmanager
def opencv_path(path: str | Path) -> Iterator[str]:
    """A name for ``path`` that OpenCV can open (to read or to write), valid inside the ``with``.

    A UTF-8 name is given as it is; any other is a symbolic link ``<tmp>/file<suffix>`` to
    the absolute path (writing through it creates ``path`` itself), removed at the end.
    """
    if is_utf8(path):
        yield str(path)
        return
    folder = tempfile.mkdtemp(prefix="pedenv-")
    try:
        suffix = "".join(c for c in Path(path).suffix if c.isascii() and (c.isalnum() or c == "."))
        link = os.path.join(folder, "file" + suffix)
        os.symlink(os.path.abspath(path), link)
        yield link
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _short(value: object, limit: int = 60) -> str:
    text = str(value)
    return text if len(text) <= limit else f"{text[:limit // 2]}...{text[-limit // 3:]}"
