"""``pedenv run --live [PORT]``: the environment model served while the run goes on, over
Foxglove's WebSocket protocol (foxglove-sdk's server), so Foxglove shows pedestrians as they appear.

The topics and messages are those of the Foxglove MCAP file (:mod:`pedenv.outputs.mcap_log`);
connect Foxglove to ``ws://HOST:PORT``. The server listens on ``127.0.0.1`` unless another host
is given (listening on every interface exposes the model to the network).
"""

from __future__ import annotations

import threading
import warnings
from pathlib import Path

import foxglove

from pedenv.errors import InputError
from pedenv.outputs.mcap_log import McapWriter

DEFAULT_PORT = 8765
DEFAULT_HOST = "127.0.0.1"
#: Seconds the end of a run waits for the server to stop: its ``stop()`` waits for every client's
#: unfinished handshake (an idle connection, a port scanner), so it is left behind after this.
STOP_TIMEOUT_S = 3.0


class LiveViewer(McapWriter):
    """A :class:`pedenv.outputs.sinks.FrameSink` logging to a WebSocket server instead of a file.

    port: TCP port, 0 for any free one (``self.port`` says which), at most 65535.
    """

    def __init__(self, port: int = DEFAULT_PORT, host: str = DEFAULT_HOST) -> None:
        if not 0 <= int(port) <= 65535:
            raise InputError(f"--live port must be in [0, 65535], got {port}")
        self._context = foxglove.Context()
        try:
            self._server = foxglove.start_server(name="pedenv", host=host, port=int(port), context=self._context)
        except Exception as exc:  # noqa: BLE001 - a port in use, a host not found
            raise InputError(f"--live: cannot serve on {host}:{port}: {exc}") from None
        self.port = self._server.port
        self.address = f"ws://{host}:{self.port}"
        self.path = Path(self.address)
        self.files: list[Path] = []
        self._writer = None
        self._open_channels()

    def close(self) -> None:
        """Stop serving, waiting at most :data:`STOP_TIMEOUT_S` (the server is left to the process's end)."""
        if self._server is not None:
            server, self._server = self._server, None
            stopping = threading.Thread(target=server.stop, name="pedenv-live-stop", daemon=True)
            stopping.start()
            stopping.join(STOP_TIMEOUT_S)
            if stopping.is_alive():
                warnings.warn(f"--live: a client of {self.address} holds the server; it is left to stop "
                              "when pedenv exits", stacklevel=2)
