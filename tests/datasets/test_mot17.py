"""MOT17 readers on the real samples (shared/samples/real/mot17) and on broken copies."""

import numpy as np
import pytest

from pedenv.datasets import mot17
from pedenv.errors import InputError

from shared_paths import REAL_SAMPLES

ROOT = REAL_SAMPLES / "mot17"


def test_seqinfo_of_mot17_05():
    info = mot17.read_seqinfo(ROOT / "MOT17-05-FRCNN" / "seqinfo.ini")
    assert (info.width, info.height, info.frame_rate, info.im_ext) == (640, 480, 14.0, ".jpg")


def test_all_sequences_match_the_readme_counts():
    folders = mot17.sequence_folders(ROOT)
    assert len(folders) == 7
    sequences = [mot17.read_sequence(f) for f in folders]
    assert sum(len(s.frames) for s in sequences) == 39
    boxes = [s.pedestrians.take(np.isin(s.pedestrians.frame, s.frames)) for s in sequences]
    assert sum(len(b) for b in boxes) == 814
    assert sum(int((b.visibility >= 0.5).sum()) for b in boxes) == 534
    heights = np.concatenate([b.boxes[:, 3] - b.boxes[:, 1] for b in boxes])
    assert heights.min() == 24 and heights.max() == 1186 and int((heights < 50).sum()) == 55
    ignore = np.concatenate([s.all_classes.take(np.isin(s.all_classes.frame, s.frames)).classes for s in sequences])
    assert [int((ignore == c).sum()) for c in mot17.IGNORE_CLASSES] == [14, 65, 44, 13]


def test_boxes_are_amodal_and_clip_to_the_image():
    seq = mot17.read_sequence(ROOT / "MOT17-11-FRCNN")
    first = seq.pedestrians.in_frame(1)
    tall = first.take(first.ids == 2)
    assert tall.boxes[0, 3] - tall.boxes[0, 1] > seq.info.height
    clipped = tall.clipped(seq.info.width, seq.info.height)
    assert clipped[0, 1] >= 0 and clipped[0, 3] <= seq.info.height
    assert seq.image_path(1).is_file()


def test_first_rows_of_mot17_02():
    seq = mot17.read_sequence(ROOT / "MOT17-02-FRCNN")
    row = seq.pedestrians.in_frame(1).take(seq.pedestrians.in_frame(1).ids == 2)
    assert row.boxes[0] == pytest.approx([1338, 418, 1338 + 167, 418 + 379])
    assert row.visibility[0] == 1.0 and row.consider[0]
    assert seq.ignore_boxes(1).shape[1] == 4 and len(seq.ignore_boxes(1)) > 0


@pytest.mark.parametrize("line, message", [
    ("1,2,3,4,5", "9 columns"),
    ("0,2,1338,418,167,379,1,1,1.0", "frame must be an integer >= 1"),
    ("1,2,1338,418,-5,379,1,1,1.0", "width and height must be >= 0"),
    ("1,2,1338,418,167,379,1,13,1.0", "class must be 1..12"),
    ("1,2,1338,418,167,379,1,1,1.5", r"visibility must be in \[0, 1\]"),
    ("1,2,1338,418,abc,379,1,1,1.0", "must be numbers"),
])
def test_bad_gt_rows_name_file_and_line(tmp_path, line, message):
    path = tmp_path / "gt.txt"
    path.write_text("1,3,586,447,85,263,1,1,1.0\n" + line + "\n")
    with pytest.raises(InputError, match=message) as info:
        mot17.read_gt(path)
    assert f"{path}:2:" in str(info.value)


def test_bad_seqinfo(tmp_path):
    path = tmp_path / "seqinfo.ini"
    path.write_text("[Sequence]\nname=x\nimDir=img1\nframeRate=30\nseqLength=600\nimWidth=wide\nimHeight=1080\nimExt=.jpg\n")
    with pytest.raises(InputError, match="imWidth must be int"):
        mot17.read_seqinfo(path)
    path.write_text("[Other]\n")
    with pytest.raises(InputError, match="no \\[Sequence\\] section"):
        mot17.read_seqinfo(path)
