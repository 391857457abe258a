"""Writer of scenes in the paper's CARLA layout (read back by :class:`~pedenv.datasets.carla.CarlaDataset`).

Everything is converted to CARLA's conventions: Unreal's left-handed axes, degrees, CARLA
transform matrices, the 20 bones synthesized from the COCO-17 ``GroundTruth.keypoints_3d``
(:func:`~pedenv.datasets.carla_bones.coco_to_bones`), 2D skeletons projected the way the
recording script does (camera-local ``(y, -z, x)`` times ``K``) and clamped to the image border.
Images are blank PNGs. The layout is 10 Hz: scenes must be generated at 10 Hz.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Iterable, Sequence
from pathlib import Path

import cv2
import numpy as np

from pedenv.datasets.carla import FRAME_RATE_HZ
from pedenv.datasets.carla_axes import cam_to_world_to_unreal, ego_to_unreal, points_to_unreal, project_unreal
from pedenv.datasets.carla_bones import coco_to_bones
from pedenv.errors import InputError
from pedenv.geometry import invert_transform
from pedenv.records import Frame, Scene

#: Simulator frame number of each scene's first frame (CARLA's never start at 0).
FIRST_FRAME_NUMBER = 1000


def write_carla(
    scenes: Iterable[Scene], output_dir: str | Path, *, first_frame: int = FIRST_FRAME_NUMBER
) -> list[Path]:
    """Write ``scenes`` as ``<output_dir>/scene<N>/{data,rgb}/`` and return the scene folders.

    Scenes already named ``scene<N>`` keep their name, the others become ``scene<i>`` by position.
    A list is checked as a whole (its names kept only if all are ``scene<N>``); any other
    iterable (a generator) is written scene by scene as it comes, named ``scene<i>``, so
    only one scene is held in memory.
    Every frame needs ground truth with ``keypoints_3d`` (or none at all: an empty frame), and
    timestamps on a 10 Hz grid; otherwise :class:`InputError` names the scene and frame.
    """
    if first_frame <= 0:
        raise InputError(f"first_frame must be positive (CARLA frame numbers do not start at 0), got {first_frame}")
    output_dir = Path(output_dir)
    if isinstance(scenes, Sequence):
        folders: Iterable[str] = _folder_names(scenes)
    else:
        folders = (f"scene{i}" for i in itertools.count())
    written = []
    for scene, folder_name in zip(scenes, folders):
        folder = output_dir / folder_name
        (folder / "data").mkdir(parents=True, exist_ok=True)
        (folder / "rgb").mkdir(parents=True, exist_ok=True)
        numbers = _frame_numbers(scene, first_frame)
        blank: dict[tuple[int, int], bytes] = {}
        for frame, number in zip(scene.frames, numbers):
            record = frame_record(frame, scene.name)  # a dict, pickled: numpy's stubs type np.save for arrays only
            np.save(folder / "data" / f"data_{number}.npy", record, allow_pickle=True)  # type: ignore[arg-type]
            size = (frame.camera.width, frame.camera.height)
            if size not in blank:
                blank[size] = cv2.imencode(".png", np.zeros((size[1], size[0], 3), np.uint8))[1].tobytes()
            (folder / "rgb" / f"img_{number}.png").write_bytes(blank[size])
        written.append(folder)
    return written


def _folder_names(scenes: Sequence[Scene]) -> list[str]:
    if (
        scenes
        and all(re.fullmatch(r"scene\d+", s.name) for s in scenes)
        and len({s.name for s in scenes}) == len(scenes)
    ):
        return [s.name for s in scenes]
    return [f"scene{i}" for i in range(len(scenes))]


def _frame_numbers(scene: Scene, first_frame: int) -> list[int]:
    if not scene.frames:
        raise InputError(f"scene {scene.name!r} has no frames to write")
    t0 = scene.frames[0].timestamp
    ticks = [(f.timestamp - t0) * FRAME_RATE_HZ for f in scene.frames]
    for frame, tick in zip(scene.frames, ticks):
        if abs(tick - round(tick)) > 1e-3:
            raise InputError(
                f"scene {scene.name!r} frame {frame.index}: timestamp {frame.timestamp:.4f} s is not on the "
                f"{FRAME_RATE_HZ:g} Hz grid of the CARLA layout; generate the scenes at {FRAME_RATE_HZ:g} Hz"
            )
    return [first_frame + int(round(t)) for t in ticks]


def frame_record(frame: Frame, scene_name: str = "") -> dict:
    """The CARLA frame dict of ``frame`` (Unreal axes, degrees, the 20 bones)."""
    k = frame.camera.intrinsics
    width, height = frame.camera.width, frame.camera.height
    cam2world = cam_to_world_to_unreal(frame.cam_to_world)
    world2cam = invert_transform(cam2world)
    xyz, ypr = ego_to_unreal(frame.ego.matrix)
    truth = frame.ground_truth
    skel_2d, skel_3d, pos_3d, bbox_2d = [], [], [], []
    if truth is not None and len(truth):
        if truth.keypoints_3d is None:
            raise InputError(f"scene {scene_name!r} frame {frame.index}: ground truth has no keypoints_3d; "
                             "the CARLA layout needs the 3D skeletons")
        bones_3d = points_to_unreal(coco_to_bones(truth.keypoints_3d))
        bones_2d = project_unreal(bones_3d, k, world2cam)
        bones_2d = np.stack([np.clip(bones_2d[..., 0], 0, width - 1), np.clip(bones_2d[..., 1], 0, height - 1)], -1)
        for b2, b3, pos in zip(bones_2d, bones_3d, points_to_unreal(truth.positions)):
            skel_2d.append(b2)
            skel_3d.append(b3)
            pos_3d.append(pos)
            bbox_2d.append(np.array([b2[:, 0].min(), b2[:, 1].min(), b2[:, 0].max(), b2[:, 1].max()]))
    return {
        "2d_skel": skel_2d,
        "3d_skel": skel_3d,
        "pos_3d": pos_3d,
        "bbox_2d": bbox_2d,
        "ego_pos": {"xyz": xyz, "yaw_pitch_roll": ypr},
        "intr_cam": np.array(k, float),
        "cam2world": cam2world,
        "world2cam": world2cam,
    }
