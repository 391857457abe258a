"""What ``pedenv run`` does so that it never loses a user's data (docs/outputs.md).

* :func:`check_paths`: every output (the folder, ``--rerun``, ``--mcap``, ``--ros-out``) is
  resolved and checked against every input (images and each image file, video, calibration,
  ego poses, bag and its files, config, manifest) and against the other outputs before anything
  is written: an output that is, holds or lies inside an input, or two outputs on one file, is
  one InputError, ``--overwrite`` or not.
* :class:`RunFolder`: an earlier run in the folder (``--overwrite``) is replaced only when the
  new one has finished: the new run is written into a sibling folder and swapped in at the end;
  a run that stops leaves the earlier one as it was. Only what pedenv wrote is removed: the
  marker file lists a run's own files, and a folder holding anything else is refused. An earlier
  ``--rerun``/``--mcap``/``--parquet``/``--ros-out`` file outside the folder is kept the same way:
  the new one is written to a hidden sibling (:data:`SIDE_PREFIX`) and renamed over it at the end.
* :class:`DiskGuard`: a full disk stops the run at a frame boundary with one line, with room
  kept back (a reserve file) so that every output can still be closed valid; a run that will
  not fit at its measured rate is warned about after its first frames; the bytes written go to
  ``run.json``.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import warnings
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from pedenv.errors import InputError
from pedenv.outputs.output_dir import glob_escape
from pedenv.paths import MARKER

if TYPE_CHECKING:
    from pedenv.outputs.sinks import ExtraOutputs

#: Bytes kept back on the output's disk while a run writes (a file of zeros, deleted before the
#: outputs close): room for the mp4 indexes, the last Parquet row group, the MCAP summary, the
#: bird's-eye plot and run.json, which together stay under 1 MB for 10,000 frames; at most a
#: quarter of the space free at the start.
RESERVE_BYTES = 4 * 2**20
#: Room kept free on top of two frames at the measured rate: bytes a writer holds and then writes at
#: once, which the rate does not see coming (an MCAP chunk, ``MCAP_CHUNK_BYTES`` of
#: :mod:`pedenv.outputs.mcap_log`, 256 KiB), and 64 KiB for the others' buffers.
BUFFERED_BYTES = 2**18 + 2**16
#: Frames after which the bytes per frame are measured and a run that will not fit is warned about.
ESTIMATE_AFTER = 3
#: The end of the first line of a marker file that lists the names its command wrote, one a line after it.
LISTED = "; --overwrite may delete the files listed below\n"
#: The first line of the marker file of a ``pedenv run`` folder.
RUN_MARKER_HEAD = f"written by pedenv run{LISTED}"
#: The start of the hidden sibling an output file outside the folder is written to while an earlier
#: file of that name waits for the swap (``.pedenv-new-<random>-<name>``, in the same folder: the rename is atomic).
SIDE_PREFIX = ".pedenv-new-"


def _resolved(path: str | Path) -> Path:
    return Path(os.path.abspath(path)).resolve()


def _identity(path: Path) -> tuple[int, int] | None:
    """(device, inode) of an existing ``path`` (hard links share it), else None."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_dev, st.st_ino


def _same(a: tuple[Path, tuple[int, int] | None], b: tuple[Path, tuple[int, int] | None]) -> bool:
    """Whether two (path, identity) pairs name one file."""
    return a[0] == b[0] or (a[1] is not None and a[1] == b[1])


def _inside(inner: Path, outer: Path) -> bool:
    return inner != outer and outer in inner.parents


def check_paths(inputs: Iterable[tuple[str, str | Path | None]], outputs: Iterable[tuple[str, str | Path | None]],
                folder: str | Path) -> None:
    """Refuse (one InputError) an output that is an input, lies inside an input folder, or is the
    output folder holding an input; and two outputs on one file. ``inputs``/``outputs``: (flag,
    path) pairs (None: not given); ``folder``: the output folder (``--output``)."""
    ins = [(flag, _resolved(p)) for flag, p in inputs if p is not None]
    outs = [(flag, _resolved(p)) for flag, p in outputs if p is not None]
    ids = {p: _identity(p) for _, p in ins + outs}  # each file stat'ed once
    out_folder = _resolved(folder)
    ids[out_folder] = _identity(out_folder)
    for oflag, out in [("--output", out_folder), *outs]:
        for iflag, source in ins:
            same = _same((out, ids[out]), (source, ids[source]))
            if same or _inside(out, source):
                where = "is" if same else "lies inside"
                raise InputError(f"{oflag} {out} {where} the input {iflag} {source}: pedenv never writes over its "
                                 "inputs; choose another path")
            if _inside(source, out):
                raise InputError(f"{oflag} {out} holds the input {iflag} {source}: pedenv never writes over or "
                                 "deletes its inputs; choose another output folder")
    for i, (aflag, a) in enumerate(outs):
        for bflag, b in outs[i + 1:]:
            if _same((a, ids[a]), (b, ids[b])):
                raise InputError(f"{aflag} and {bflag} name one file, {a}: give each output its own file")


def input_files(folder: str | Path | None, limit: int = 100_000) -> list[Path]:
    """The files inside an input folder (a rosbag2 folder's, a dataset's) that a check of the folder
    itself does not cover, among the first ``limit``: links (an output on their target is elsewhere)
    and files with other hard links. The others cannot be an output outside the folder."""
    if folder is None or not Path(folder).is_dir():
        return []
    found: list[Path] = []
    scanned = 0
    for root, _dirs, _files in os.walk(folder):
        with contextlib.suppress(OSError), os.scandir(root) as entries:
            for entry in entries:
                if entry.is_dir(follow_symlinks=False):
                    continue
                scanned += 1
                if entry.is_symlink() or _links(entry) > 1:
                    found.append(Path(entry.path))
        if scanned >= limit:
            break
    return found


def _links(entry: os.DirEntry) -> int:
    try:
        return entry.stat(follow_symlinks=False).st_nlink
    except OSError:
        return 1


class RunFolder:
    """The output folder of one run: ``work`` is where it writes, ``final`` where it ends up.

    A new or empty ``final`` is written in place. An earlier pedenv run there (``overwrite``) is
    kept until :meth:`commit`: the new run goes to a fresh sibling folder, swapped in at the end;
    :meth:`abandon` (a run that stopped) leaves the earlier run as it was and the new one beside it.
    """

    def __init__(self, final: Path, work: Path) -> None:
        self.final, self.work = final, work
        self.sides: list[tuple[str, Path]] = []  # (prefix of the hidden sibling, the file it replaces at the end)

    @property
    def beside(self) -> bool:
        """Whether the run is written beside an earlier one (swapped in by :meth:`commit`)."""
        return self.work != self.final

    def final_path(self, path: str | Path) -> Path:
        """Where ``path`` (in ``work``) will be once the run is committed."""
        path = Path(path)
        for prefix, final in self.sides:  # a file beside an earlier one (a Rerun scene's <stem>-<scene>.rrd too)
            if path.parent == final.parent and path.name.startswith(prefix):
                return final.parent / path.name[len(prefix):]
        try:
            return self.final / path.relative_to(self.work)
        except ValueError:
            return path

    def output_path(self, path: str | Path | None, overwrite: bool) -> Path | None:
        """Where the run writes the output file ``path``: in ``work`` for one inside the folder; for one
        outside it with an earlier file there (``overwrite``), a fresh hidden sibling renamed over it by
        :meth:`commit`; else ``path``."""
        if path is None:
            return None
        path = Path(path)
        if self.final == path or _resolved(self.final) in _resolved(path).parents or not overwrite:
            return self.work_path(path)
        earlier = path.exists() or any(path.parent.glob(f"{glob_escape(path.stem)}-*{path.suffix}"))
        if not earlier:
            return path
        try:
            fd, name = tempfile.mkstemp(prefix=SIDE_PREFIX, suffix=f"-{path.name}", dir=path.parent)
        except OSError as exc:
            raise InputError(f"{path}: cannot write the new file beside the earlier one: "
                             f"{exc.strerror or exc}") from None
        os.close(fd)
        self.sides.append((Path(name).name[: -len(path.name)], path))
        return Path(name)

    def side_files(self) -> list[Path]:
        """What was written beside earlier files (a scene's or a method's ``<stem>-<name>`` too), found on disk."""
        found = [p for prefix, final in self.sides for p in final.parent.glob(f"{glob_escape(prefix)}*")]
        return [p for p in found if p.stat().st_size > 0]  # the empty name made for the file: never written

    def _side_files(self, files: Iterable[str | Path]) -> list[tuple[Path, Path]]:
        """(written, final) of ``files`` written beside earlier ones, and the hidden siblings nothing wrote."""
        pairs = {Path(f): self.final_path(f) for f in files}
        pairs = {w: f for w, f in pairs.items() if w != f and w.name.startswith(SIDE_PREFIX)}
        for prefix, final in self.sides:
            placeholder = final.parent / f"{prefix}{final.name}"
            if placeholder not in pairs and placeholder.exists():
                placeholder.unlink()  # created empty and never written (a Rerun recording split into scenes)
        return list(pairs.items())

    def work_path(self, path: str | Path | None) -> Path | None:
        """``path`` in ``final`` moved to ``work`` (others as they are)."""
        if path is None:
            return None
        try:
            return self.work / _resolved(path).relative_to(_resolved(self.final))
        except ValueError:
            return Path(path)

    def list_files(self, *more: str) -> None:
        """Write the marker listing the names this run wrote and ``more`` (what a later ``--overwrite`` may
        delete)."""
        list_files(self.work, "pedenv run", *more)

    def commit(self, files: Iterable[str | Path] = ()) -> None:
        """The new run in place of the earlier one (nothing to do when written in place), and each of
        ``files`` (the outputs written) written beside an earlier file renamed over it."""
        for written, final in self._side_files(files):
            try:
                written.replace(final)
            except OSError as exc:
                raise InputError(f"{final}: cannot put the new file in place of the earlier one "
                                 f"({exc.strerror or exc}); the new one is {written}") from None
        if not self.beside:
            return
        old = Path(tempfile.mkdtemp(prefix=f".{self.final.name}.pedenv-old-", dir=self.final.parent))
        try:
            self.final.rename(old / "run")
            self.work.rename(self.final)
        except OSError as exc:
            if (old / "run").exists() and not self.final.exists():
                (old / "run").rename(self.final)
            raise InputError(f"output folder {self.final}: cannot put the new run in place of the earlier one "
                             f"({exc.strerror or exc}); the new run is in {self.work}") from None
        shutil.rmtree(old, ignore_errors=True)

    def abandon(self, frames: int | None, files: Iterable[str | Path] = ()) -> None:
        """A run that stopped: the earlier run and earlier files stay; the new one's frames stay beside
        them (or none, removed; None: not counted, kept)."""
        for written, final in self._side_files(files):
            if frames == 0:
                written.unlink(missing_ok=True)
            else:
                what = "the new one is" if frames is None else f"this run's {frames} frames are"
                warnings.warn(f"the run stopped; the earlier {final} is kept as it was, {what} in {written}",
                              stacklevel=2)
        if not self.beside or frames is None:
            return
        if frames == 0:
            shutil.rmtree(self.work, ignore_errors=True)
            return
        warnings.warn(f"the run stopped; the earlier run in {self.final} is kept as it was, this run's {frames} "
                      f"frames are in {self.work}", stacklevel=2)


@contextlib.contextmanager
def outside_files(folder: str | Path, extra: ExtraOutputs) -> Iterator[ExtraOutputs]:
    """``extra`` with each ``--rerun``/``--mcap``/``--ros-out`` file outside ``folder`` that replaces an
    earlier one (``extra.overwrite``) written to a hidden sibling (:meth:`RunFolder.output_path`): renamed
    over the earlier files when the block ends, kept beside them (a warning) when it raises."""
    import dataclasses

    sides = RunFolder(Path(folder), Path(folder))
    moved = dataclasses.replace(extra, rerun=sides.output_path(extra.rerun, extra.overwrite),
                                mcap=sides.output_path(extra.mcap, extra.overwrite),
                                ros=sides.output_path(extra.ros, extra.overwrite))
    try:
        yield moved
    except BaseException:
        sides.abandon(None, sides.side_files())
        raise
    sides.commit(sides.side_files())


def list_files(folder: Path, command: str, *more: str) -> None:
    """The marker of ``folder`` listing the names ``command`` wrote there and ``more``: what a later
    ``--overwrite`` may delete (:func:`prepare_folder` refuses anything else)."""
    with contextlib.suppress(OSError):  # a full disk, a folder gone: the marker of prepare_output_dir stays
        names = sorted({p.name for p in folder.iterdir() if p.name != MARKER} | set(more))
        (folder / MARKER).write_text(f"written by {command}{LISTED}" + "".join(f"{n}\n" for n in names),
                                     encoding="utf-8", errors="surrogateescape")  # names that are not UTF-8 too


def extra_paths(extra: ExtraOutputs | None) -> list[tuple[str, Path | None]]:
    """(flag, path) of the per-frame output files in ``extra`` (for :func:`check_paths`)."""
    if extra is None:
        return []
    return [("--rerun", extra.rerun), ("--mcap", extra.mcap), ("--ros-out", extra.ros), ("--parquet", extra.parquet)]


def check_outputs(folder: str | Path, inputs: Iterable[tuple[str, str | Path | None]],
                  extra: ExtraOutputs | None) -> None:
    """:func:`check_paths` of ``folder`` and ``extra``'s files against ``inputs`` and the files inside
    each input folder (a dataset's, links followed)."""
    given = [(flag, p) for flag, p in inputs if p is not None]
    check_paths([*given, *((flag, f) for flag, p in given for f in input_files(p))], extra_paths(extra), folder)


def prepare_folder(folder: str | Path, inputs: Iterable[tuple[str, str | Path | None]],
                   extra: ExtraOutputs | None, *, overwrite: bool, command: str) -> Path:
    """A command's output folder checked and prepared: no output on an input (:func:`check_paths`; an
    input folder's files are checked one by one), then, with ``overwrite``, an earlier folder whose marker
    lists its files refused when it holds anything else, then
    :func:`~pedenv.outputs.output_dir.prepare_output_dir`. Call :func:`list_files` when the command ends."""
    from pedenv.outputs.output_dir import holds_files, prepare_output_dir

    check_outputs(folder, inputs, extra)
    if overwrite and holds_files(Path(folder)) and (Path(folder) / MARKER).is_file():
        _refuse_foreign_files(Path(folder))
    return prepare_output_dir(folder, overwrite=overwrite, command=command)


def open_run_folder(folder: str | Path, *, overwrite: bool, command: str) -> RunFolder:
    """Prepare ``folder`` for a run (:func:`pedenv.outputs.output_dir.prepare_output_dir`), or, when it holds
    an earlier pedenv run and ``overwrite`` is given, a fresh sibling to write beside it. A folder whose
    marker lists the run's files refuses anything else found there."""
    from pedenv.outputs.output_dir import holds_files, prepare_output_dir

    final = Path(folder)
    if not (overwrite and holds_files(final) and (final / MARKER).is_file()):
        return RunFolder(final, prepare_output_dir(final, overwrite=overwrite, command=command))
    _refuse_foreign_files(final)
    try:
        work = Path(tempfile.mkdtemp(prefix=f"{final.name}.pedenv-new-", dir=final.parent))
    except OSError as exc:
        raise InputError(f"output folder {final}: cannot write the new run beside the earlier one: "
                         f"{exc.strerror or exc}") from None
    prepare_output_dir(work, command=command)
    return RunFolder(final, work)


def _refuse_foreign_files(folder: Path) -> None:
    """InputError naming the first thing in ``folder`` its marker does not list (when it lists names)."""
    head, _, names = (folder / MARKER).read_text(encoding="utf-8", errors="surrogateescape").partition("\n")
    if not head.startswith("written by ") or not f"{head}\n".endswith(LISTED):
        return  # an older marker, or one written when the command started: the whole folder is pedenv's
    listed = set(names.splitlines()) | {MARKER}
    foreign = sorted(p.name for p in folder.iterdir() if p.name not in listed)
    if foreign:
        raise InputError(f"output folder {folder} holds {folder / foreign[0]}, which pedenv did not write; "
                         "--overwrite only replaces pedenv's own files: move it or choose another folder")


class DiskGuard:
    """Watches the free space of the folders a run writes to (see the module doc).

    ``folders``: where the outputs go (one reserve file in the first, the output folder).
    ``total``: the frames of the recording (0: not known).
    """

    def __init__(self, folders: Iterable[Path], total: int) -> None:
        self.folders = list(dict.fromkeys(Path(f) for f in folders))
        self.total = total
        self.reserve: Path | None = self.folders[0] / ".pedenv-reserve"
        size = min(RESERVE_BYTES, _free(self.folders[0]) // 4)
        try:
            with self.reserve.open("wb") as f:
                os.posix_fallocate(f.fileno(), 0, max(size, 1))
        except (OSError, AttributeError):
            self.release()  # no reserve (a file system without fallocate): the margin alone
        self.start = {f: _free(f) for f in self.folders}  # after the reserve: what the outputs take is measured
        self.rate = 0.0  # bytes per frame, measured
        self.warned = False

    def check(self, frames_done: int) -> None:
        """Before a frame is written: InputError (the reserve released) when its outputs would not fit."""
        for folder in self.folders:
            free = _free(folder)
            used = max(self.start[folder] - free, 0)
            if frames_done:
                self.rate = max(self.rate, used / frames_done)
            if free < 2 * self.rate + BUFFERED_BYTES:
                self.release()
                raise InputError(f"{folder}: the disk is full ({free / 1e6:.1f} MB free, a frame takes "
                                 f"{self.rate / 1e6:.2f} MB); the run stopped after {frames_done} frames, every output "
                                 "is valid up to there")
            left = self.total - frames_done
            if not self.warned and frames_done >= ESTIMATE_AFTER and left > 0 and self.rate * left > free:
                self.warned = True
                warnings.warn(f"{folder}: at {self.rate / 1e6:.2f} MB per frame the {left} frames left need "
                              f"{self.rate * left / 1e6:.0f} MB and {free / 1e6:.0f} MB are free: the run will stop "
                              "when the disk is full (--video-out writes the overlays as one small video)",
                              stacklevel=2)

    def release(self) -> None:
        """Give the reserved room back (before the outputs close)."""
        if self.reserve is not None:
            with contextlib.suppress(OSError):
                self.reserve.unlink(missing_ok=True)
            self.reserve = None

    def __enter__(self) -> DiskGuard:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def _free(folder: Path) -> int:
    """Bytes free to an unprivileged writer under ``folder`` (its nearest existing parent)."""
    existing = next(p for p in (folder, *folder.parents) if p.exists())
    st = os.statvfs(existing)
    return st.f_bavail * st.f_frsize


def bytes_written(paths: Iterable[Path]) -> int:
    """Bytes in ``paths`` (files, or folders counted whole)."""
    total = 0
    for path in dict.fromkeys(paths):
        if path.is_file():
            total += path.stat().st_size
        elif path.is_dir():
            total += sum(f.stat().st_size for f in path.rglob("*") if f.is_file())
    return total
