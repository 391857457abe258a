"""Issue 32 for ``pedenv run --manifest`` and ``pedenv detect``: an output folder that holds one of
their inputs is refused, ``--overwrite`` or not, and the input's bytes stay as they were."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_run_safety import digest, recording

from pedenv.apps.batch import run_manifest
from pedenv.apps.detect import annotate_images
from pedenv.apps.options import OutputOptions
from pedenv.errors import InputError
from pedenv.paths import MARKER
from pedenv.records import Detections


def _earlier(folder: Path, command: str) -> None:
    """``folder`` as an earlier run of ``command`` left it (its marker)."""
    folder.mkdir(parents=True)
    (folder / MARKER).write_text(f"written by {command}; --overwrite may delete this folder's contents\n")


@pytest.mark.parametrize("moved", ["images", "manifest"])
def test_run_manifest_overwrite_refuses_a_folder_holding_a_recording_or_the_manifest(tmp_path, moved):
    out = tmp_path / "o"
    _earlier(out, "pedenv run --manifest")
    rec = recording(out / "drive" if moved == "images" else tmp_path / "drive", frames=2)
    manifest = (out if moved == "manifest" else tmp_path) / "drives.csv"
    manifest.write_text("name,images,calibration,ego_poses\n"
                        f"d1,{rec['images']},{rec['calibration']},{rec['ego_poses']}\n")
    before = digest(out)
    flag = "--manifest" if moved == "manifest" else "manifest row 1 images"
    with pytest.raises(InputError, match=rf"^--output {out} holds the input {flag} "):
        run_manifest(manifest, OutputOptions(out, overwrite=True))
    assert digest(out) == before


class _Nobody:
    name = "nobody"

    def detect(self, image, geometry=None):  # noqa: ARG002 - the image backends' detect
        return Detections.empty()


def test_detect_overwrite_refuses_a_folder_holding_an_image_or_the_calibration(tmp_path):
    out = tmp_path / "o"
    _earlier(out, "pedenv detect")
    rec = recording(out / "rec", frames=1)
    image = rec["images"] / "f000.png"
    before = digest(out)
    with pytest.raises(InputError, match=rf"^--output {out} holds the input image {image}"):
        annotate_images([image], out, _Nobody(), overwrite=True)
    other = recording(tmp_path / "other", frames=1)["images"] / "f000.png"
    with pytest.raises(InputError, match=rf"^--output {out} holds the input --calibration"):
        annotate_images([other], out, _Nobody(), overwrite=True, calibration=rec["calibration"])
    assert digest(out) == before


def test_detect_lists_its_files_and_overwrite_refuses_a_users_file(tmp_path):
    image = recording(tmp_path / "rec", frames=1)["images"] / "f000.png"
    out = tmp_path / "o"
    annotate_images([image], out, _Nobody())
    assert (out / MARKER).read_text().splitlines()[1:] == ["detections.json", "f000_pose.png"]
    annotate_images([image], out, _Nobody(), overwrite=True)
    (out / "mine.txt").write_text("mine")
    with pytest.raises(InputError, match=r"mine\.txt, which pedenv did not write"):
        annotate_images([image], out, _Nobody(), overwrite=True)
    assert (out / "mine.txt").read_text() == "mine"


def test_a_marker_lists_names_that_are_not_utf8_and_overwrite_takes_them_back(tmp_path):
    import os

    from pedenv.apps.output_safety import list_files, prepare_folder

    out = tmp_path / "o"
    prepare_folder(out, [], None, overwrite=False, command="pedenv detect")
    odd = out / os.fsdecode(b"x\xff_pose.png")
    odd.write_bytes(b"written by pedenv")
    list_files(out, "pedenv detect")
    assert b"x\xff_pose.png\n" in (out / MARKER).read_bytes()  # the name as the disk has it
    prepare_folder(out, [], None, overwrite=True, command="pedenv detect")  # pedenv's own file: taken back
    assert not odd.exists()
