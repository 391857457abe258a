"""The ``pedenv`` command line: thin commands, each calling one library function.

Each command group lives in its own module and registers itself on :data:`app`.
"""

from __future__ import annotations

# Importing the modules registers their commands on ``app``.
from pedenv.cli import (
    bag_commands,  # noqa: E402,F401
    calibrate_commands,  # noqa: E402,F401
    core_commands,  # noqa: E402,F401
    detection_commands,  # noqa: E402,F401
    pose_commands,  # noqa: E402,F401
)
from pedenv.cli.app import app, main

__all__ = ["app", "main"]
