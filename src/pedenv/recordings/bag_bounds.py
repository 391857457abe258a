"""Bounds a bag is held to before anything in it is decompressed: no bomb takes the memory or the disk.

A few megabytes of zstd can hold gigabytes of zeros. Every size is therefore read from the
bag's own records first and checked, and every decompression is cut at the size announced:

- ROS 1 chunks (bz2, lz4): each decompressed to at most ``bag.max_message_bytes``.
- MCAP chunks: each chunk's uncompressed size (its index record) and the chunks open at once
  (the reader merges chunks that overlap in time) must stay within ``bag.max_message_bytes``;
  a chunk that decompresses to more than it announced is refused at that size.
- rosbag2 ``compression_mode: message``: each message decompressed to at most ``max_message_bytes``.
- rosbag2 ``compression_mode: file``: decompressed into a temporary folder (removed when the bag
  closes, on errors and Ctrl-C too) of at most :data:`MAX_FILE_DECOMPRESSION_RATIO` times the
  bag's own size.
- ``metadata.yaml``'s message counts: whole numbers, and what the storage holds (a count that
  disagrees is warned about and the storage's used; a topic whose type disagrees is refused).
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Callable
from contextlib import ExitStack
from pathlib import Path
from typing import Any

from pedenv.errors import InputError

#: Most bytes a file-compressed rosbag2 (``compression_mode: file``) is decompressed to, as a
#: multiple of its own size: zstd compresses camera images and CDR about 2 to 4 times, so 10 leaves
#: room for dark or static footage while a bomb (1000 times and more) is refused before its disk is used.
MAX_FILE_DECOMPRESSION_RATIO = 10
#: The temporary space a file-compressed rosbag2 always gets, bytes (a small bag's database
#: holds its schema and indexes, more than 10 times its compressed size).
MIN_TEMPORARY_BYTES = 16 * 2**20


class BombError(Exception):
    """A compressed record that would decompress beyond its bound (the reader's own exception type
    would read as a damaged bag; this one is reported as what it is)."""


def bounded_decompress(data: bytes, compression: str, size: int, limit: int) -> bytes:
    """``data`` (zstd, lz4 or '' for none) decompressed, refused above ``size`` bytes (what its
    record announces) or above ``limit`` (the largest allowed)."""
    if size > limit:
        raise BombError(f"a {compression} chunk announces {size} bytes uncompressed ({len(data)} compressed), "
                        f"more than bag.max_message_bytes ({limit}); a decompression bomb or a corrupt size field")
    if compression == "":
        return data
    if compression == "zstd":
        from backports import zstd

        decompressor: Any = zstd.ZstdDecompressor()
    elif compression == "lz4":
        import lz4.frame

        decompressor = lz4.frame.LZ4FrameDecompressor()
    else:
        raise BombError(f"unsupported chunk compression {compression!r} (zstd, lz4)")
    raw = decompressor.decompress(data, max_length=size + 1)
    if len(raw) > size:
        raise BombError(f"a {compression} chunk decompresses to more than the {size} bytes it announces "
                        "(a decompression bomb or a corrupt chunk)")
    return raw


def install_bounds(limit: int) -> None:
    """Make the ``rosbags`` readers decompress through bounded decompressors: MCAP chunks within
    their announced size and ``limit`` (:func:`bounded_decompress`; rosbags' own take the size but
    do not hold to it), ROS 1 chunks (whose size rosbags does not keep) within ``limit``. Called
    before each bag is opened (ROS 1 keeps the decompressor of each chunk it indexes)."""
    from rosbags.rosbag1 import reader as ros1
    from rosbags.rosbag2 import storage_mcap

    def make(compression: str) -> Callable[[bytes, int], bytes]:
        return lambda data, size: bounded_decompress(data, compression, size, limit)

    storage_mcap.DECOMPRESSORS.update({"zstd": make("zstd"), "lz4": make("lz4")})
    ros1.decompressors.update({"bz2": lambda data: _ros1_chunk(data, "bz2", limit),
                               "lz4": lambda data: _ros1_chunk(data, "lz4", limit)})


def _ros1_chunk(data: bytes, compression: str, limit: int) -> bytes:
    """A ROS 1 chunk (bz2 or lz4) decompressed, refused beyond ``limit`` bytes."""
    if compression == "bz2":
        import bz2

        decompressor: Any = bz2.BZ2Decompressor()
    else:
        import lz4.frame

        decompressor = lz4.frame.LZ4FrameDecompressor()
    raw = decompressor.decompress(data, max_length=limit + 1)
    if len(raw) > limit:
        raise BombError(f"a {compression} chunk of {len(data)} bytes decompresses to more than bag.max_message_bytes "
                        f"({limit}); a decompression bomb or a corrupt chunk")
    return raw


def check_chunks(path: Path, readers: list[Any], limit: int) -> None:
    """InputError when an indexed MCAP chunk, or the chunks that overlap in time (read at once),
    hold more than ``limit`` bytes uncompressed."""
    from rosbags.rosbag2.storage_mcap import McapReader

    for reader in readers:
        if not isinstance(reader, McapReader):
            continue  # ROS 1 chunks and sqlite3 rows: read one at a time, within max_message_bytes
        chunks = sorted(reader.chunks, key=lambda c: c.message_start_time)
        open_chunks: list[Any] = []
        for chunk in chunks:
            open_chunks = [c for c in open_chunks if c.message_end_time >= chunk.message_start_time] + [chunk]
            held = sum(c.uncompressed_size for c in open_chunks)
            if held > limit:
                what = "a chunk" if len(open_chunks) == 1 else f"{len(open_chunks)} chunks overlapping in time"
                verb = "holds" if len(open_chunks) == 1 else "hold"
                raise InputError(f"{path}: {what} at file offset {chunk.chunk_start_offset} {verb} {held} bytes "
                                 f"uncompressed ({chunk.compressed_size} compressed), more than "
                                 f"bag.max_message_bytes ({limit}); a decompression bomb or a corrupt size field")


def message_decompress(where: str, raw: bytes, limit: int) -> bytes:
    """One zstd message of a ``compression_mode: message`` rosbag2, at most ``limit`` bytes."""
    from backports import zstd

    try:
        out = zstd.ZstdDecompressor().decompress(raw, max_length=limit + 1)
    except zstd.ZstdError as exc:
        raise InputError(f"{where}: the zstd message cannot be decompressed: {exc}") from None
    if len(out) > limit:
        raise InputError(f"{where}: decompresses to more than bag.max_message_bytes ({limit}) from {len(raw)} "
                         "bytes; a decompression bomb or a runaway message")
    return out


def read_metadata(folder: Path) -> dict:
    """The ``rosbag2_bagfile_information`` mapping of ``folder/metadata.yaml`` ({} when unreadable:
    the reader then says why)."""
    import yaml

    try:
        data = yaml.safe_load((folder / "metadata.yaml").read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return {}
    info = data.get("rosbag2_bagfile_information") if isinstance(data, dict) else None
    return info if isinstance(info, dict) else {}


def decompressed_copy(folder: Path, info: dict, stack: ExitStack) -> Path:
    """A rosbag2 ``compression_mode: file`` folder decompressed into a temporary folder (removed
    by ``stack``), at most :data:`MAX_FILE_DECOMPRESSION_RATIO` times the bag's size: its path."""
    import yaml
    from backports import zstd

    names = [Path(str(p)).name for p in info.get("relative_file_paths") or []]
    files = [folder / n for n in names]
    own = sum(f.stat().st_size for f in files if f.is_file())
    budget = max(MAX_FILE_DECOMPRESSION_RATIO * own, MIN_TEMPORARY_BYTES)
    tmp = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="pedenv-bag-")))
    free = shutil.disk_usage(tmp).free
    if budget > free:
        budget = free - 2**20
    out_names = []
    for file in files:
        if not file.is_file():
            raise InputError(f"{folder}: {file.name}, listed in metadata.yaml, is missing")
        target = tmp / (file.name[:-5] if file.name.endswith(".zstd") else file.name)
        try:
            with file.open("rb") as src, zstd.open(src, "rb") as unz, target.open("wb") as dst:
                while block := unz.read(2**20):
                    budget -= len(block)
                    if budget < 0:
                        raise InputError(
                            f"{folder}: {file.name} decompresses to more than {MAX_FILE_DECOMPRESSION_RATIO} times "
                            f"the bag's {own} bytes (at least {MIN_TEMPORARY_BYTES // 2**20} MiB; "
                            "pedenv.recordings.bag_bounds.MAX_FILE_DECOMPRESSION_RATIO) or than the free temporary "
                            "disk: a decompression bomb, or decompress the bag yourself")
                    dst.write(block)
        except (zstd.ZstdError, EOFError) as exc:
            raise InputError(f"{folder}: {file.name} is not a whole zstd file: {exc}") from None
        out_names.append(target.name)
    meta = dict(info, relative_file_paths=out_names, compression_mode="", compression_format="")
    meta["files"] = [dict(f, path=n) for f, n in zip(info.get("files") or [], out_names) if isinstance(f, dict)]
    (tmp / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": meta}))
    return tmp


def check_counts(path: Path, reader: Any) -> str | None:
    """``metadata.yaml``'s counts and types against what a rosbag2's storage holds: InputError for a
    count that is no whole number or a type that disagrees; for counts that disagree, the line to
    warn with (returned) and the storage's counts put in ``reader.connections``."""
    storage: dict[str, tuple[set[str], int]] = {}
    for s in getattr(reader, "storages", []):
        for c in s.connections:
            types, count = storage.get(c.topic, (set(), 0))
            storage[c.topic] = (types | {c.msgtype}, count + int(c.msgcount))
    lost = []
    for i, conn in enumerate(reader.connections):
        count = conn.msgcount
        if not isinstance(count, int) or isinstance(count, bool) or count < 0:
            raise InputError(f"{path}: metadata.yaml gives topic {conn.topic} a message_count of {count!r}, not a "
                             "count (a whole number, 0 or more)")
        types, held = storage.get(conn.topic, (set(), 0))
        if types and conn.msgtype not in types:
            raise InputError(f"{path}: metadata.yaml gives topic {conn.topic} the type {conn.msgtype}, its storage "
                             f"holds {', '.join(sorted(types))}: the two disagree (an edited metadata.yaml?)")
        if held != count:
            lost.append(f"{conn.topic} {held} of {count}")
            reader.connections[i] = conn._replace(msgcount=held)
    if not lost:
        return None
    return (f"{path}: the storage holds fewer or more messages than metadata.yaml counts ({'; '.join(lost)}): "
            "messages lost or the metadata edited; reading what the storage holds")
