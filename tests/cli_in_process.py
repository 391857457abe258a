"""Run the ``pedenv`` command in this process, as a user would type it."""

import sys

import pytest

from pedenv.cli import main


def pedenv(monkeypatch, capsys, *args) -> tuple[int, str, str]:
    """Run ``pedenv args`` in this process: (exit code, stdout, stderr)."""
    monkeypatch.setattr(sys, "argv", ["pedenv", *map(str, args)])
    monkeypatch.setenv("COLUMNS", "1000")
    with pytest.raises(SystemExit) as done:
        main()
    out = capsys.readouterr()
    return done.value.code or 0, out.out, out.err
