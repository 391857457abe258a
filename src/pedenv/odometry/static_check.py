"""Whether a camera declared static (``--static``) really stands still: its background's flow between frames.

A fixed camera's background stays where it is (on ``vtest.avi``, a camera over a plaza, the tracks'
median flow against the first frame stays below 0.1 px over its 795 frames); a camera on a moving car
sees its whole view flow (KITTI raw 0002 at 9 m/s: about 12 px a frame). Pairs of frames
:data:`PAIR_GAP_FRAMES` apart, spread over the recording, are compared by the odometry's own tracks
(:func:`pedenv.odometry.features.track`: FAST corners, Lucas-Kanade flow there and back); people walking
through move a minority of the corners, so the median flow is the background's.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from pedenv.errors import InputError
from pedenv.odometry.features import detect_corners, track

#: Frames between the two frames of a pair: 5 (0.5 s at 10 Hz, 0.2 s at 25 fps) lets a car at walking
#: pace move its view by pixels (a shorter recording: its first and last frames). Measured on the real
#: MOT17 samples (first to last frame, 4-8 frames at 14-30 fps): the fixed cameras of MOT17-02, -04
#: and -09 at most 0.47 px, the walking and bus cameras of MOT17-05, -10, -11 and -13 at least 13.8 px.
PAIR_GAP_FRAMES = 5
#: Pairs compared, spread evenly over the recording (over a video's first :data:`VIDEO_FRAMES`).
PAIRS = 8
#: A video is read from its start, up to this many frames (a long video is not decoded whole for the check).
VIDEO_FRAMES = 600
#: Median flow, pixels, from which a pair's camera moved: four times the largest seen on a fixed
#: camera (vtest.avi, 0.095 px against its first frame: :data:`pedenv.odometry.motion.MIN_PARALLAX_PX`
#: is 0.5 px) and far below a driving car's.
MOVED_PX = 2.0
#: Share of the pairs (with enough tracks to judge) that must show motion for the camera to be refused:
#: a bus passing close to a fixed camera moves most of one pair's corners, not half the recording's.
MOVED_SHARE = 0.5
#: Fewest tracks for a pair to be judged (the odometry's :data:`~pedenv.odometry.motion.MIN_TRACKS`).
MIN_PAIR_TRACKS = 40


def pair_gap(frames: int) -> int:
    """Frames between a pair's two among ``frames`` frames: :data:`PAIR_GAP_FRAMES`, or fewer in a short recording."""
    return max(min(PAIR_GAP_FRAMES, frames - 1), 0)


def pair_starts(frames: int) -> list[int]:
    """The first frames of the pairs compared among ``frames`` frames (none with fewer than two)."""
    gap = pair_gap(frames)
    if gap == 0:
        return []
    return [int(i) for i in np.unique(np.linspace(0, frames - 1 - gap, PAIRS).round())]


def pair_flows(read: Callable[[int], np.ndarray | None], frames: int) -> list[tuple[int, float]]:
    """(first frame of the pair, median flow in pixels) of up to :data:`PAIRS` pairs of grey frames
    :data:`PAIR_GAP_FRAMES` apart spread over ``frames`` frames, ``read(index)`` giving frame ``index``
    (H, W) uint8; pairs with fewer than :data:`MIN_PAIR_TRACKS` tracks are left out."""
    flows, gap = [], pair_gap(frames)
    for start in pair_starts(frames):
        first, second = read(start), read(start + gap)
        if first is None or second is None:  # a video shorter than its header said
            continue
        p0, p1, _ = track(first, second, detect_corners(first, np.full(first.shape[:2], 255, np.uint8)))
        if len(p0) >= MIN_PAIR_TRACKS:
            flows.append((int(start), float(np.median(np.linalg.norm(p1 - p0, axis=1)))))
    return flows


def check_static(*, images: str | Path | None = None, video: str | Path | None = None) -> list[tuple[int, float]]:
    """Refuse a recording declared static whose camera moves (InputError, one line: the frames that
    show it and what to give instead); returns the pairs' (first frame, median flow px) that were judged."""
    read, frames, name = _reader(images, video)
    flows = pair_flows(read, frames)
    moved = [(start, flow) for start, flow in flows if flow >= MOVED_PX]
    if flows and len(moved) >= MOVED_SHARE * len(flows):
        start, flow = max(moved, key=lambda m: m[1])
        raise InputError(
            f"{name}: declared --static, but the camera moves: its background moved a median {flow:.1f} px "
            f"from frame {start} to frame {start + pair_gap(frames)} ({len(moved)} of {len(flows)} frame pairs "
            f"moved {MOVED_PX:g} px or more); give the camera's ego poses (--ego-poses), or drop --static to have them "
            f"estimated from the images (with a --calibration holding cam_to_vehicle)")
    return flows


def _reader(images: str | Path | None, video: str | Path | None) -> tuple[Callable[[int], np.ndarray | None], int, str]:
    """(read(index) -> grey frame, frame count, the recording's name) of an image folder or a video's start."""
    import cv2

    from pedenv.images import read_image_rgb

    if images is not None:
        from pedenv.recordings.footage import IMAGE_SUFFIXES

        folder = Path(images)
        paths = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES) if folder.is_dir() else []
        return (lambda i: cv2.cvtColor(read_image_rgb(paths[i]), cv2.COLOR_RGB2GRAY)), len(paths), str(folder)
    from pedenv.video_files import video_capture

    assert video is not None  # one of the two (the recording's own checks name a missing one)
    grey: dict[int, np.ndarray] = {}  # only the frames of the pairs are kept
    with video_capture(video) as cap:
        frames = min(int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) or VIDEO_FRAMES, VIDEO_FRAMES)
        wanted = {i + gap for i in pair_starts(frames) for gap in (0, pair_gap(frames))}
        for index in range(max(wanted, default=-1) + 1):
            ok, bgr = cap.read()
            if not ok:
                break
            if index in wanted:
                grey[index] = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY)
    return grey.get, frames, str(video)
