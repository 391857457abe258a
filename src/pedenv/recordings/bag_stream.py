"""A truncated MCAP bag read front to back: every complete message before the cut.

A recorder that crashed leaves an MCAP file without its summary and footer, which the
indexed reader refuses. :class:`StreamingMcap` reads such a file record by record with the
``mcap`` library's stream reader (the ``ros`` extra brings it) and stops at the cut; it offers
what :class:`~pedenv.recordings.bag_source.BagSource` uses of a rosbags reader:
``connections`` and ``messages(connections)``, and says where the file was cut.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection, Iterator
from pathlib import Path
from typing import Any


class StreamingMcap:
    """An MCAP file read sequentially; ``cut`` is None until a read reaches a cut-off record."""

    def __init__(self, path: Path, limit: int) -> None:
        self.path = path
        self.limit = limit  # most bytes a chunk may hold uncompressed (bag.max_message_bytes)
        self.connections: list = []
        self.cut: str | None = None

    def _records(self) -> Iterator:
        from mcap.records import Chunk
        from mcap.stream_reader import StreamReader

        from pedenv.recordings.bag_bounds import BombError

        with self.path.open("rb") as f:
            try:
                for record in StreamReader(f, record_size_limit=2**34, emit_chunks=True).records:
                    if isinstance(record, Chunk):
                        yield from _chunk_records(record, self.limit)
                    else:
                        yield record
            except BombError:
                raise
            except Exception as exc:  # noqa: BLE001 - the cut shows as any read error
                self.cut = str(exc) or type(exc).__name__

    def open(self) -> None:
        """One pass over the file: its channels, their schemas and their complete messages."""
        from mcap.records import Channel, Message, Schema
        from rosbags.interfaces import Connection, ConnectionExtRosbag2, MessageDefinition, MessageDefinitionFormat

        schemas: dict[int, Schema] = {}
        channels: dict[int, Channel] = {}
        counts: dict[int, int] = {}
        for record in self._records():
            if isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message):
                counts[record.channel_id] = counts.get(record.channel_id, 0) + 1
        for cid, channel in sorted(channels.items()):
            schema = schemas.get(channel.schema_id)
            fmt = MessageDefinitionFormat.IDL if schema and schema.encoding == "ros2idl" else \
                MessageDefinitionFormat.MSG
            definition = MessageDefinition(fmt, schema.data.decode() if schema else "")
            self.connections.append(Connection(cid, channel.topic, schema.name if schema else "", definition, "",
                                               counts.get(cid, 0), ConnectionExtRosbag2("cdr", []), self))

    def close(self) -> None:
        pass

    def messages(self, connections: Collection) -> Iterator[tuple[object, int, bytes]]:
        """(connection, log time ns, raw CDR) of ``connections`` in file order, up to the cut."""
        from mcap.records import Message

        wanted = {c.id: c for c in connections}
        for record in self._records():
            if isinstance(record, Message) and record.channel_id in wanted:
                yield wanted[record.channel_id], record.log_time, record.data


def _chunk_records(chunk: Any, limit: int) -> Iterator:
    """The records of one MCAP chunk, decompressed within its announced size and ``limit``."""
    from mcap.stream_reader import breakup_chunk

    from pedenv.recordings.bag_bounds import bounded_decompress

    raw = bounded_decompress(chunk.data, chunk.compression, chunk.uncompressed_size, limit)
    yield from breakup_chunk(dataclasses.replace(chunk, compression="", data=raw))
