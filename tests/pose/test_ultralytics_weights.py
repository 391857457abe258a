"""Loading ``.pt`` weights never runs code from the file (issue 10, item 1)."""

from __future__ import annotations

import os

import pytest

from pedenv.errors import InputError


class _RunsCommand:
    """Unpickling this runs a shell command (the payload of the issue)."""

    def __init__(self, command: str) -> None:
        self.command = command

    def __reduce__(self):
        return os.system, (self.command,)


@pytest.mark.ultralytics
def test_pickled_command_in_weights_is_refused(tmp_path, monkeypatch):
    import torch

    from pedenv.pose.ultralytics_backend import UltralyticsPose

    monkeypatch.chdir(tmp_path)
    weights = tmp_path / "evil.pt"
    torch.save({"model": _RunsCommand("touch PWNED")}, weights)
    with pytest.raises(InputError, match=r"evil\.pt: cannot load the weights"):
        UltralyticsPose(weights=weights)
    assert not (tmp_path / "PWNED").exists()
