"""Open a ROS bag without a ROS installation: rosbag2 (sqlite3 or MCAP), a single ``.mcap``, ROS 1 ``.bag``.

The pure-Python ``rosbags`` library (the ``ros`` extra) reads the containers and the
message definitions stored in them; :class:`BagSource` turns each of its failures into one
:class:`~pedenv.errors.InputError` line naming the bag, the topic and the message index.
"""

from __future__ import annotations

import functools
from collections.abc import Collection, Iterable, Iterator
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias

from pedenv.errors import InputError, require_extra
from pedenv.recordings.bag_bounds import (
    BombError,
    check_chunks,
    check_counts,
    decompressed_copy,
    install_bounds,
    message_decompress,
    read_metadata,
)

if TYPE_CHECKING:
    from pedenv.recordings.bag_stream import StreamingMcap

#: A message larger than this (bytes) is refused as corrupt before it is decoded, and so is a
#: compressed MCAP chunk (or chunks read at once) announcing more (:mod:`pedenv.recordings.bag_bounds`):
#: an image at pedenv's pixel limit (64 MP, :data:`pedenv.images.MAX_IMAGE_PIXELS`) is 256 MB in
#: rgba8 (an 8K RGB image 100 MB), so 256 MiB only stops a size field that lies, a runaway message
#: or a decompression bomb, and keeps a bag's reading within 1 GB. Raising it admits larger messages.
MAX_MESSAGE_BYTES = 256 * 2**20
#: A decoded ROS message or a rosbags connection or typestore: rosbags builds its message classes
#: at run time and mypy does not follow it (pyproject), so these are ``Any``, named for the reader.
RosMessage: TypeAlias = Any
RosConnection: TypeAlias = Any
RosTypestore: TypeAlias = Any


@dataclass(frozen=True)
class TopicSummary:
    """One topic of a bag: message type (``pkg/msg/Name``), message count and the span of
    its receive times (nanoseconds; first == last for one message)."""

    name: str
    msgtype: str
    count: int
    first_ns: int
    last_ns: int

    @property
    def rate_hz(self) -> float | None:
        """Mean message rate over the topic's span, or None for fewer than 2 messages."""
        span = (self.last_ns - self.first_ns) / 1e9
        return (self.count - 1) / span if self.count > 1 and span > 0 else None


@dataclass(frozen=True)
class BagMessage:
    """One decoded message: topic, index within the topic (0-based), receive time (ns), message."""

    topic: str
    index: int
    log_ns: int
    msg: RosMessage


def _bag_kind(path: Path) -> str:
    if path.is_dir():
        if not (path / "metadata.yaml").is_file():
            raise InputError(f"{path}: not a rosbag2 folder (no metadata.yaml in it)")
        return "rosbag2"
    if not path.is_file():
        raise InputError(f"{path}: bag not found")
    if path.suffix == ".bag":
        return "ros1"
    if path.suffix == ".mcap":
        return "mcap"
    raise InputError(f"{path}: not a bag (a rosbag2 folder with metadata.yaml, a .mcap file or a ROS 1 .bag)")


class BagSource:
    """A bag opened for reading (a context manager); ``topics`` lists what it holds."""

    def __init__(self, path: str | Path, *, max_message_bytes: int = MAX_MESSAGE_BYTES) -> None:
        require_extra("rosbags", "ros", "--bag")
        if not 1024 <= max_message_bytes <= 2**40:
            raise InputError(f"bag.max_message_bytes must be in [1024, 2**40], got {max_message_bytes!r}")
        self.path = Path(path)
        self.kind = _bag_kind(self.path)
        self.max_message_bytes = max_message_bytes
        self._stack = ExitStack()
        self._reader: Any = None
        self.is_ros1 = self.kind == "ros1"
        self.zstd_messages = False
        #: The warning line when the storage holds other counts than metadata.yaml (None: they agree).
        self.counts_differ: str | None = None

    def __enter__(self) -> BagSource:
        from rosbags.rosbag1 import Reader as Reader1
        from rosbags.rosbag2 import Reader as Reader2
        from rosbags.rosbag2.storage_mcap import McapReader

        opener: Any = {"ros1": Reader1, "rosbag2": Reader2, "mcap": McapReader}[self.kind]
        install_bounds(self.max_message_bytes)
        try:
            folder = self.path
            if self.kind == "rosbag2" and str(read_metadata(folder).get("compression_mode", "")).lower() == "file":
                folder = decompressed_copy(folder, read_metadata(folder), self._stack)
            try:
                reader = opener(folder)
                reader.open()
            except Exception:
                reader = _cut_mcap(folder, self.max_message_bytes)  # a recording cut short: the messages before it
                if reader is None:
                    raise
            self._stack.callback(reader.close)
            self._reader = reader
            self._check_sizes(reader)
            self.typestore = _typestore(reader.connections, self.is_ros1)
        except (InputError, KeyboardInterrupt):
            self._stack.close()
            raise
        except BombError as exc:
            self._stack.close()
            raise InputError(f"{self.path}: {exc}") from None
        except Exception as exc:  # noqa: BLE001 - any library failure is a damaged bag
            self._stack.close()
            raise InputError(f"{self.path}: cannot open the bag (truncated or damaged?): {_why(exc)}") from None
        self.connections = list(reader.connections)
        self.topics = self._summaries()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stack.close()

    @property
    def reader(self) -> Any:
        """The ``rosbags`` reader (or :class:`~pedenv.recordings.bag_stream.StreamingMcap`) of the open bag."""
        return self._reader

    def _check_sizes(self, reader: Any) -> None:
        """The bounds of :mod:`pedenv.recordings.bag_bounds` a bag's index and metadata allow checking
        before a message is read; ``compression_mode: message`` is decompressed here (bounded), not by the reader."""
        inner = getattr(reader, "storage", reader)  # rosbags' Reader of a rosbag2 folder wraps its DirectoryReader
        check_chunks(self.path, [inner, *getattr(inner, "storages", [])], self.max_message_bytes)
        if self.kind == "rosbag2" and hasattr(inner, "storages"):
            self.counts_differ = check_counts(self.path, inner)
            if inner.metadata.compression_mode == "message":
                inner.metadata = inner.metadata._replace(compression_mode=None)
                self.zstd_messages = True

    def _summaries(self) -> dict[str, TopicSummary]:
        topics: dict[str, TopicSummary] = {}
        for c in self.connections:
            old = topics.get(c.topic)
            count = int(c.msgcount) + (old.count if old else 0)
            topics[c.topic] = TopicSummary(c.topic, c.msgtype, count, 0, 0)
        return dict(sorted(topics.items()))

    def topics_of(self, *msgtypes: str) -> list[str]:
        """The topics whose type is one of ``msgtypes`` (``pkg/msg/Name``), sorted."""
        return [t.name for t in self.topics.values() if t.msgtype in msgtypes]

    def messages(self, topics: Collection[str], *, to_the_cut: bool = False) -> Iterator[BagMessage]:
        """The messages of ``topics`` in receive-time order, decoded. A message that cannot be
        read or decoded raises InputError naming the bag, topic and message index, and so does
        the end of a file cut short, unless ``to_the_cut`` (then its messages end there)."""
        conns = [c for c in self.connections if c.topic in topics]
        counts = dict.fromkeys(topics, 0)
        if not conns:
            return
        last: dict[str, Any] = {"topic": "?", "index": -1}
        stream = self._reader.messages(connections=conns)
        try:
            for conn, log_ns, raw in stream:
                index = counts[conn.topic]
                counts[conn.topic] += 1
                last.update(topic=conn.topic, index=index)
                yield BagMessage(conn.topic, index, int(log_ns), self._decode(conn, index, raw))
        except InputError:
            raise
        except BombError as exc:
            after = f"after topic {last['topic']} message {last['index']}" if last["index"] >= 0 else "first chunk"
            raise InputError(f"{self.path}: {after}: {exc}") from None
        except Exception as exc:  # noqa: BLE001 - the container itself is damaged past this point
            raise InputError(f"{self.path}: damaged or truncated after topic {last['topic']} message "
                             f"{last['index']}: {_why(exc)}") from None
        cut = getattr(self._reader, "cut", None)
        if cut and not to_the_cut:
            raise InputError(f"{self.path}: the file is cut off after topic {last['topic']} message {last['index']} "
                             f"(truncated: {cut}); the messages before it were read")

    def log_spans(self) -> dict[str, TopicSummary]:
        """``topics`` with each topic's first and last receive time (reads every message, decodes none)."""
        spans: dict[str, list[int]] = {}
        try:
            stream = self._reader.messages(connections=self.connections)
            for conn, log_ns, _ in stream:
                span = spans.setdefault(conn.topic, [int(log_ns), int(log_ns)])
                span[0], span[1] = min(span[0], int(log_ns)), max(span[1], int(log_ns))
        except Exception as exc:  # noqa: BLE001 - a damaged container
            raise InputError(f"{self.path}: damaged or truncated: {_why(exc)}") from None
        return {name: TopicSummary(t.name, t.msgtype, t.count, *spans.get(name, (0, 0)))
                for name, t in self.topics.items()}

    def _decode(self, conn: RosConnection, index: int, raw: bytes) -> RosMessage:
        where = f"{self.path}: topic {conn.topic} message {index}"
        if self.zstd_messages:
            raw = message_decompress(where, raw, self.max_message_bytes)
        if len(raw) > self.max_message_bytes:
            raise InputError(f"{where}: {len(raw)} bytes, more than bag.max_message_bytes "
                             f"({self.max_message_bytes}); a corrupt size field or a runaway message")
        try:
            if self.is_ros1:
                return self.typestore.deserialize_ros1(raw, conn.msgtype)
            return self.typestore.deserialize_cdr(raw, conn.msgtype)
        except Exception as exc:  # noqa: BLE001 - a size field that lies shows up as any decode error
            raise InputError(f"{where} ({conn.msgtype}) cannot be decoded (a size field beyond the "
                             f"message's {len(raw)} bytes?): {_why(exc)}") from None


def _cut_mcap(path: Path, limit: int) -> StreamingMcap | None:
    """A :class:`~pedenv.recordings.bag_stream.StreamingMcap` of the MCAP file at ``path`` (or the one
    MCAP file of a rosbag2 folder) that holds channels, or None."""
    from pedenv.recordings.bag_stream import StreamingMcap

    files = sorted(path.glob("*.mcap")) if path.is_dir() else [path]
    if len(files) != 1:
        return None
    with files[0].open("rb") as f:
        if f.read(8) != b"\x89MCAP0\r\n":
            return None
    reader = StreamingMcap(files[0], limit)
    reader.open()
    return reader if reader.connections else None


def _why(exc: Exception) -> str:
    text = " ".join(str(a) for a in exc.args) or type(exc).__name__
    return text.splitlines()[0] if text.strip() else type(exc).__name__


@functools.lru_cache(maxsize=64)
def _definitions(kind: str, text: str, msgtype: str) -> dict[str, Any]:
    """The types one stored message definition declares (parsed once per process: a bag is opened
    twice per run, and parsing is most of the cost of opening it)."""
    from rosbags.typesys import get_types_from_idl, get_types_from_msg

    if kind == "msg":
        return dict(get_types_from_msg(text, msgtype))
    types: dict[str, Any] = {}
    sep = "=" * 80 + "\n"
    for part in text.split(sep)[1:] if text.startswith(sep) else [text]:
        types.update(get_types_from_idl(part.split("\n", 1)[1] if part.startswith("IDL: ") else part))
    return types


def _typestore(connections: Iterable[RosConnection], is_ros1: bool) -> RosTypestore:
    """A typestore of the bag's own message definitions (a type changed between ROS releases is
    read as the bag wrote it); a bag without them (rosbag2 sqlite3 before Iron) gets the types of
    ROS 2 Humble (ROS 1: Noetic) for what it lacks."""
    from rosbags.interfaces import MessageDefinitionFormat
    from rosbags.typesys import Stores, get_typestore

    types: dict[str, Any] = {}
    lacking = False
    for c in connections:
        if c.msgdef.format in (MessageDefinitionFormat.MSG, MessageDefinitionFormat.IDL) and c.msgdef.data:
            kind = "msg" if c.msgdef.format == MessageDefinitionFormat.MSG else "idl"
            types.update(_definitions(kind, c.msgdef.data, c.msgtype))
        else:
            lacking = True
    if lacking:
        store = get_typestore(Stores.ROS1_NOETIC if is_ros1 else Stores.ROS2_HUMBLE)
        store.register({k: v for k, v in types.items() if k not in store.fielddefs})
        return store
    store = get_typestore(Stores.EMPTY)
    store.register(types)
    return store
