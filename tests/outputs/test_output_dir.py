"""Output folders (issue 10.4, 10.5): a bad folder is one InputError; two runs never mix."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.errors import InputError
from pedenv.images import write_image
from pedenv.outputs.jsonl import EnvironmentWriter
from pedenv.outputs.output_dir import MARKER, prepare_output_dir


def test_new_and_empty_folders_are_prepared(tmp_path):
    out = prepare_output_dir(tmp_path / "a" / "b", command="test")
    assert out.is_dir() and (out / MARKER).is_file()
    (tmp_path / "empty").mkdir()
    assert prepare_output_dir(tmp_path / "empty").is_dir()


@pytest.mark.parametrize("make, message", [
    (lambda t: t / "file.txt", r"output folder .*file\.txt is an existing file"),
    (lambda t: t / "file.txt" / "out", r"output folder .*file\.txt/out lies under .*file\.txt, which is a file"),
    (lambda t: t / "file.txt" / "a" / "b", r"lies under .*file\.txt, which is a file"),
])
def test_a_file_in_the_way_is_refused(tmp_path, make, message):
    (tmp_path / "file.txt").write_text("mine")
    with pytest.raises(InputError, match=message):
        prepare_output_dir(make(tmp_path))
    assert (tmp_path / "file.txt").read_text() == "mine"


def test_unwritable_folder_is_refused():
    # /proc refuses new folders even to root (the tests may run as root, which ignores file modes)
    with pytest.raises(InputError, match=r"output folder /proc/pedenv-test/out cannot be written"):
        prepare_output_dir("/proc/pedenv-test/out")


def test_earlier_run_is_refused_then_replaced_with_overwrite(tmp_path):
    out = prepare_output_dir(tmp_path / "out")
    (out / "environment.jsonl").write_text('{"frame": 0}\n')
    (out / "overlays").mkdir()
    (out / "overlays" / "000099.png").write_bytes(b"stale")
    with pytest.raises(InputError, match=r"output folder .*out is not empty; pass --overwrite"):
        prepare_output_dir(out)
    assert (out / "environment.jsonl").read_text() == '{"frame": 0}\n'  # the earlier run is untouched
    prepare_output_dir(out, overwrite=True)
    assert sorted(p.name for p in out.iterdir()) == [MARKER]


def test_overwrite_never_clears_a_folder_pedenv_did_not_write(tmp_path):
    (tmp_path / "thesis.tex").write_text("years of work")
    with pytest.raises(InputError, match=r"not empty and was not written by pedenv \(no \.pedenv-output file\)"):
        prepare_output_dir(tmp_path, overwrite=True)
    assert (tmp_path / "thesis.tex").read_text() == "years of work"


def test_environment_file_that_is_a_folder_is_refused(tmp_path):
    (tmp_path / "environment.jsonl").mkdir()
    with pytest.raises(InputError, match=r"environment model .*environment\.jsonl is a folder"), \
            EnvironmentWriter(tmp_path / "environment.jsonl"):
        pass


def test_overlays_that_is_a_file_is_refused(tmp_path):
    (tmp_path / "overlays").write_text("")
    with pytest.raises(InputError, match=r"cannot create the folder of image .*overlays/000000\.png"):
        write_image(tmp_path / "overlays" / "000000.png", np.zeros((4, 4, 3), np.uint8))
