"""``pedenv calibrate``: a camera estimated from the people in its first frames (the warm-up).

The warm-up reads the first :data:`WARMUP_SECONDS` of a video (or the first
:data:`WARMUP_MAX_FRAMES` images of a folder, whichever is fewer), finds the people with the
pose backend, links them from frame to frame and fits the camera
(:func:`pedenv.calibration.fit.estimate_camera`). ``pedenv run`` without ``--calibration`` runs
the same warm-up before its frames, then refines a static camera's estimate as it runs
(:class:`Refinement`).
"""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np

from pedenv.apps.options import PoseOptions, RecordingSource
from pedenv.calibration.estimate import CameraEstimate
from pedenv.calibration.fit import NETWORK_BODY, BodyModel, estimate_camera, fitted_heads
from pedenv.calibration.linking import BoxLinker
from pedenv.calibration.observations import Observations, observations_of
from pedenv.calibration.road import TravelWatcher
from pedenv.calibration.vehicle import estimate_mounting
from pedenv.errors import InputError
from pedenv.pose.base import PoseBackend
from pedenv.records import Camera, Detections, EgoPose, Frame
from pedenv.state import EnvironmentState

#: The warm-up: the first this many seconds of a video (its own frame rate) ...
WARMUP_SECONDS = 20.0
#: ... and at most this many frames (an image folder: the first this many images). 200 frames of
#: the built-in static scene (10 Hz, about 45 people) fix its focal length within 3 %; on a CPU
#: the network takes about a second a frame, so the warm-up stays a few minutes.
WARMUP_MAX_FRAMES = 200
#: When the people of a warm-up do not fix the camera (too few, or a focal length or height too
#: uncertain) it goes on, a warm-up's length at a time, up to this many seconds of a video and
#: frames: vtest.avi (10 Hz, a camera about 7 m up) fixes its focal length only over its whole
#: 795 frames (1-sigma 8 %; 200, 400 and 600 frames leave it at 11 % or more).
WARMUP_LONGEST_SECONDS, WARMUP_LONGEST_FRAMES = 120.0, 1200
#: Pose backends that run a real network (whose keypoints sit as :data:`NETWORK_BODY` says).
NETWORK_BACKENDS = ("onnx", "ultralytics")


@dataclass(frozen=True)
class WarmUp:
    """What the warm-up saw: the people (``people``), the frames read, the last image (RGB)."""

    people: Observations
    frames: int
    image: np.ndarray


def warmup_frames(images: str | Path | None, video: str | Path | None,
                  limit: int = WARMUP_MAX_FRAMES, seconds: float = WARMUP_SECONDS) -> Iterator[tuple[int, np.ndarray]]:
    """(index, (H, W, 3) uint8 RGB) of the warm-up's frames: a folder's first ``limit`` images
    (sorted by name) or a video's first ``seconds``, at most ``limit`` frames."""
    from pedenv.images import read_image_rgb
    from pedenv.recordings.footage import IMAGE_SUFFIXES

    if video is not None:
        import cv2

        from pedenv.video_files import video_capture

        with video_capture(video) as cap:
            rate = cap.get(cv2.CAP_PROP_FPS)
            count = min(limit, math.ceil(seconds * rate)) if rate and rate > 0 else limit
            for index in range(count):
                ok, bgr = cap.read()
                if not ok:
                    return
                yield index, cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
        return
    assert images is not None
    folder = Path(images)
    if not folder.is_dir():
        raise InputError(f"{folder}: image folder not found")
    paths = sorted(p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)[:limit]
    if not paths:
        raise InputError(f"{folder}: no images ({', '.join(IMAGE_SUFFIXES)}) in the folder")
    for index, path in enumerate(paths):
        yield index, read_image_rgb(path)


def _detect(backend: PoseBackend, index: int, image: np.ndarray) -> Detections:
    """One image's skeletons: the backend's whole-image ``detect`` where it has one, else the
    backend on a frame (a placeholder camera: the backend must not need the true one)."""
    detect = getattr(backend, "detect", None)
    if detect is not None:
        return detect(image)
    camera = Camera.from_fov(image.shape[1], image.shape[0])
    return backend(Frame(index, float(index), camera, EgoPose(np.zeros(3), np.eye(3)), image=image))


def block_frames(video: str | Path | None, limit: int = WARMUP_MAX_FRAMES) -> int:
    """Frames of one warm-up: ``limit``, and for a video at most its first :data:`WARMUP_SECONDS`."""
    if video is None:
        return limit
    import cv2

    from pedenv.video_files import video_capture

    with video_capture(video) as cap:
        rate = cap.get(cv2.CAP_PROP_FPS)
    return min(limit, math.ceil(WARMUP_SECONDS * rate)) if rate and rate > 0 else limit


def warm_up(images: str | Path | None, video: str | Path | None, backend: PoseBackend,
            fit: Callable[[WarmUp], CameraEstimate], block: int,
            road: TravelWatcher | None = None) -> tuple[WarmUp, CameraEstimate]:
    """The people of the recording's first frames and the camera ``fit`` to them, tried after every
    ``block`` frames until it stands, up to :data:`WARMUP_LONGEST_SECONDS` and
    :data:`WARMUP_LONGEST_FRAMES` (at least one block); the last refusal is raised (one line) when
    none stood, or at once when a whole block showed nobody. ``road`` (or None) watches the frames on
    the way (a vehicle camera's direction of travel, :class:`~pedenv.calibration.road.TravelWatcher`)."""
    from pedenv.calibration.refusals import CalibrationRefused

    linker, parts, last, count = BoxLinker(), [], None, 0
    frames = warmup_frames(images, video, max(block, WARMUP_LONGEST_FRAMES), max(WARMUP_LONGEST_SECONDS,
                                                                                  WARMUP_SECONDS))
    frames = road.watch(frames) if road is not None else frames
    refused: CalibrationRefused | None = None
    for index, image in frames:
        det = _detect(backend, index, image)
        parts.append(observations_of(det, index, linker(det.boxes)))
        last, count = image, count + 1
        if count % block == 0:
            seen = WarmUp(Observations.concat(parts), count, last)
            try:
                return seen, fit(seen)
            except CalibrationRefused as exc:
                if not len(seen.people):
                    raise
                refused = exc
    if last is None:
        raise InputError("the recording holds no readable frame to estimate the camera from")
    seen = WarmUp(Observations.concat(parts), count, last)
    if count % block or refused is None:
        return seen, fit(seen)
    raise refused


def body_of(backend_name: str) -> BodyModel:
    """Where ``backend_name``'s keypoints sit on a person: a real network's, or the anatomical table."""
    return NETWORK_BODY if backend_name in NETWORK_BACKENDS else BodyModel()


def estimate_from(warmup: WarmUp, backend_name: str, intrinsics: np.ndarray | None = None,
                  road: TravelWatcher | None = None, static: bool = False,
                  position: tuple[float, float] = (0.0, 0.0)) -> CameraEstimate:
    """The camera fitted to the warm-up's people (``intrinsics`` (3, 3) pixels fix focal length
    and principal point when given); ``road``: a vehicle camera's travel directions seen during the
    warm-up, combined with the people (:func:`pedenv.calibration.vehicle.estimate_mounting`);
    ``static``: a fixed camera, whose tracks' ground points give each walker's direction of travel
    (:func:`~pedenv.calibration.fit.estimate_camera` ``walking``); ``position``: a vehicle camera's
    place in the vehicle frame (``camera_position``, :attr:`CameraEstimate.position`)."""
    size = (warmup.image.shape[1], warmup.image.shape[0])
    focal = None if intrinsics is None else float(intrinsics[0, 0])
    centre = None if intrinsics is None else (float(intrinsics[0, 2]), float(intrinsics[1, 2]))
    if road is not None and focal is not None:
        estimate = estimate_mounting(warmup.people, size, focal=focal, centre=centre, body=body_of(backend_name),
                                     road=road.cue(), scale=road.scale())
    else:
        estimate = estimate_camera(warmup.people, size, focal=focal, centre=centre, body=body_of(backend_name),
                                   walking=static)
    return dataclasses.replace(estimate, position=position)


def road_watcher(intrinsics: np.ndarray | None, mount: str,
                 ego_length: Callable[[int, int], float] | None = None) -> TravelWatcher | None:
    """A vehicle camera with its intrinsics: a watcher of its direction of travel during the warm-up
    (:class:`~pedenv.calibration.road.TravelWatcher`; ``ego_length``: the ego poses' metres between two
    frames, for the road's scale); else None (a static camera has no road cue)."""
    return TravelWatcher(intrinsics, ego_length) if mount == "vehicle" and intrinsics is not None else None


def ego_lengths(ego_poses: str | Path | None, images: str | Path | None, video: str | Path | None,
                fps: float | None = None, start_time: float | None = None) -> Callable[[int, int], float] | None:
    """Where ``ego_poses`` (a CSV) are given: the metres the car moved between two frames of the
    recording (their indices), the frames timed as ``pedenv run`` times them; else None."""
    if ego_poses is None:
        return None
    from pedenv.calibration.road import ego_length
    from pedenv.recordings.ego_poses import load_ego_poses
    from pedenv.recordings.footage import folder_frames

    trajectory = load_ego_poses(ego_poses)
    start = float(trajectory.timestamps[0] if start_time is None else start_time)
    if images is not None:
        stamps = np.array([t for _, t in folder_frames(Path(images), fps, start)])
    else:
        assert video is not None
        stamps = start + np.arange(WARMUP_LONGEST_FRAMES) / (fps or _video_rate(video))
    return ego_length(trajectory, stamps)


def _video_rate(video: str | Path) -> float:
    import cv2

    from pedenv.video_files import video_capture

    with video_capture(video) as cap:
        rate = float(cap.get(cv2.CAP_PROP_FPS))
    if not rate > 0:
        raise InputError(f"{video}: the video gives no frame rate to time its frames against the ego poses; give --fps")
    return rate


def write_estimate(folder: Path, estimate: CameraEstimate, warmup: WarmUp, backend_name: str,
                   mount: str = "static") -> dict:
    """``calibration.yaml`` (the input format, ``estimated: true``), ``calibration.json`` (the
    summary) and ``calibration.png`` (horizon, ground grid, people) in ``folder``; returns the summary."""
    from pedenv.calibration.files import write_calibration
    from pedenv.calibration.picture import draw_calibration
    from pedenv.images import write_image

    write_calibration(folder / "calibration.yaml", estimate, mount)
    people = warmup.people
    shown = people.subset(np.linspace(0, len(people) - 1, min(len(people), 400)).astype(int))
    heads = fitted_heads(estimate, shown, body_of(backend_name))
    write_image(folder / "calibration.png", draw_calibration(warmup.image, estimate, shown, heads))
    summary = {**estimate.summary(), "mount": mount, "warmup_frames": warmup.frames, "pose_backend": backend_name}
    (folder / "calibration.json").write_text(json.dumps(summary, indent=2, allow_nan=False) + "\n")
    return summary


def calibrate(*, output: str | Path, source: RecordingSource, backend: PoseBackend, overwrite: bool = False,
              frames: int = WARMUP_MAX_FRAMES) -> dict:
    """Estimate the camera of ``source`` (its ``images`` folder or ``video``) from its warm-up's
    people and write ``calibration.yaml``, ``calibration.json`` and ``calibration.png`` into ``output``.

    ``source.calibration``: a YAML with the image size and the intrinsics or ``fov_deg`` (no
    ``cam_to_vehicle`` needed): the focal length is then taken from it. ``source.static``: ``mount:
    static`` (else ``vehicle``, the vehicle origin under the camera; its ``ego_poses``, where given,
    give the road's scale: :func:`ego_lengths`, timed with ``fps`` and ``start_time``).
    ``backend.name`` says where its keypoints sit on a person (:func:`body_of`). Returns the
    summary (``calibration.json``). Raises :class:`~pedenv.calibration.refusals.CalibrationRefused`
    (one line: what could not be estimated and what to give instead) before ``output`` is touched.
    """
    from pedenv.outputs.output_dir import prepare_output_dir
    from pedenv.recordings.footage import load_camera_position, load_intrinsics

    images, video, calibration, static = source.images, source.video, source.calibration, source.static
    if (images is None) == (video is None):
        raise InputError("give exactly one of an image folder (--images) or a video (--video)")
    if video is not None and not Path(video).is_file():
        raise InputError(f"{video}: video file not found")
    k, size, position = None, None, (0.0, 0.0)
    if calibration is not None:
        width, height, k = load_intrinsics(calibration)
        size, position = (width, height), load_camera_position(calibration, static)
    ego = None if static else ego_lengths(source.ego_poses, images, video, source.fps, source.start_time)
    road = road_watcher(k, "static" if static else "vehicle", ego)

    def fit(warmup: WarmUp) -> CameraEstimate:
        if size is not None and (warmup.image.shape[1], warmup.image.shape[0]) != size:
            raise InputError(f"{calibration}: the calibration is {size[0]}x{size[1]} pixels, the frames "
                             f"{warmup.image.shape[1]}x{warmup.image.shape[0]}")
        return estimate_from(warmup, backend.name, k, road, static, position)

    warmup, estimate = warm_up(images, video, backend, fit, block_frames(video, frames), road)
    folder = prepare_output_dir(output, overwrite=overwrite, command="pedenv calibrate")
    return write_estimate(folder, estimate, warmup, backend.name, "static" if static else "vehicle")


@dataclass(frozen=True)
class SelfCalibration:
    """``pedenv run`` without a placed camera: the estimate, the warm-up it came from, the
    calibration file the run reads (``path``, in a temporary folder) and the pose backend's name."""

    estimate: CameraEstimate
    warmup: WarmUp
    path: Path
    backend_name: str
    mount: str = "static"
    intrinsics: np.ndarray | None = None  # (3, 3) pixels when the calibration gave them

    def refinement(self) -> Refinement | None:
        """A static camera's :class:`Refinement` over the run, None on a vehicle."""
        return Refinement(self) if self.mount == "static" else None

    def widened(self, write: Callable[[tuple[EnvironmentState, Frame]], None]
                ) -> Callable[[tuple[EnvironmentState, Frame]], None]:
        """``write`` (the run's writer stage) given each state with every position's covariance
        widened by the estimate's uncertainty (:func:`pedenv.calibration.spread.widen_state`)."""
        from pedenv.calibration.spread import widen_state

        def widened_write(result: tuple[EnvironmentState, Frame]) -> None:
            write((widen_state(result[0], self.estimate, result[1].ego), result[1]))

        return widened_write

    def write(self, folder: Path) -> dict:
        """The estimate's files into the run's output ``folder`` (:func:`write_estimate`), the
        temporary calibration file removed; returns the summary."""
        summary = write_estimate(folder, self.estimate, self.warmup, self.backend_name, self.mount)
        shutil.rmtree(self.path.parent, ignore_errors=True)
        return summary


def needs_estimate(images: str | Path | None, video: str | Path | None, calibration: str | Path | None,
                   static: bool) -> bool:
    """Whether ``pedenv run``'s recording (images or a video) needs its camera estimated: a static
    camera without a calibration, or any camera whose calibration gives no ``cam_to_vehicle``."""
    from pedenv.recordings.footage import has_mounting

    if images is None and video is None:
        return False
    if calibration is None:
        return static
    return not has_mounting(calibration)


def self_calibrate(images: str | Path | None, video: str | Path | None, calibration: str | Path | None,
                   backend: PoseBackend | None, backend_name: str, device: str = "auto",
                   mount: str = "static", ego_length: Callable[[int, int], float] | None = None) -> SelfCalibration:
    """The warm-up of ``pedenv run`` without a placed camera: the camera estimated from the first
    frames' people (``backend``, else the onnx network's whole-image ``far`` detection on ``device``),
    written as a plain calibration file in a temporary folder for the run to read. ``ego_length``
    (:func:`ego_lengths`): a vehicle's given ego poses, whose step lengths give the road's scale."""
    import tempfile

    from pedenv.calibration.files import calibration_mapping
    from pedenv.recordings.footage import load_camera_position, load_intrinsics

    k = load_intrinsics(calibration)[2] if calibration is not None else None
    position = load_camera_position(calibration, mount == "static") if calibration is not None else (0.0, 0.0)
    if backend is None:
        from pedenv.detection import backend_options, create_detector

        backend = create_detector(backend_name, **backend_options(backend_name, None, None, "far", device=device))
    road = road_watcher(k, mount, ego_length)
    warmup, estimate = warm_up(images, video, backend, partial(estimate_from, backend_name=backend_name,
                                                               intrinsics=k, road=road, static=mount == "static",
                                                               position=position),
                               block_frames(video, WARMUP_MAX_FRAMES), road)
    mapping = {key: v for key, v in calibration_mapping(estimate, mount).items()
               if key not in ("estimated", "uncertainty")}
    path = Path(tempfile.mkdtemp(prefix="pedenv-calibration-")) / "calibration.yaml"
    import yaml

    path.write_text(yaml.safe_dump(mapping, sort_keys=False), encoding="utf-8")
    return SelfCalibration(estimate, warmup, path, backend_name, mount, k)


def estimate_for_source(source: RecordingSource, pose: PoseOptions,
                        backend: PoseBackend | None) -> tuple[RecordingSource, SelfCalibration | None]:
    """``pedenv run``'s recording with its camera: as given, or (a static camera without a calibration,
    or any camera whose calibration has no ``cam_to_vehicle``) estimated in the warm-up and read
    from a temporary calibration file. A vehicle camera's estimated mounting puts the vehicle
    origin on the road under the camera, its x axis along the camera's horizontal view. The model
    then runs with its settings as for a given camera: the estimate's error is one error shared by
    every position, which its uncertainty added to the written covariances carries
    (:meth:`SelfCalibration.widened`); widening the fused method's camera spreads instead moved
    weight from the ground cue to the height cue and doubled the positions' error on the built-in
    plaza (docs/any_camera.md)."""
    if source.bag is not None or not needs_estimate(source.images, source.video, source.calibration, source.static):
        return source, None
    ego = None if source.static else ego_lengths(source.ego_poses, source.images, source.video, source.fps,
                                                 source.start_time)
    found = self_calibrate(source.images, source.video, source.calibration, backend, pose.backend or "onnx",
                           pose.device, "static" if source.static else "vehicle", ego)
    return dataclasses.replace(source, calibration=found.path), found


#: After the warm-up, ``pedenv run`` (a static camera it estimated) keeps the upright people of
#: every frame it runs and fits the camera again, to all of them, each time this many new frames
#: have passed: 300 frames are 10 s of a 30 Hz video; the fit takes 0.3 s of a CPU for 1000
#: person-images and 1.4 s for vtest.avi's 3794, a few ms per frame spread over the interval.
REFINE_EVERY_FRAMES = 300
#: The refits stop once this many person-images are kept (the estimate then stays): the fit's
#: time grows with them (a few seconds here), and its uncertainty no longer shrinks much (it is
#: held by the crowd's mean height, ``CROWD_MEAN_STD_M``, and by each person's repeated images).
REFINE_MAX_OBSERVATIONS = 10000


class Refinement:
    """The camera of ``pedenv run``'s static self-calibration refined as more people are seen.

    ``step`` wraps the pipeline's model step: each frame after the warm-up is given the camera
    in force (the latest estimate), its people are kept, and every :data:`REFINE_EVERY_FRAMES`
    frames the camera is fitted to all people kept so far. A new estimate applies from the next
    frame on; a frame already run is never run or written again. A refit the people do not fix
    (:class:`~pedenv.calibration.refusals.CalibrationRefused`) leaves the estimate as it was
    and is noted in :attr:`history`. ``widened`` gives each written state the covariance of
    the estimate its frame ran with.
    """

    def __init__(self, found: SelfCalibration) -> None:
        self.found = found
        self.estimate = found.estimate
        self.camera: Camera | None = None  # None until a refit: the calibration file's camera as read
        self.kept = [found.warmup.people]
        self.count = len(found.warmup.people)
        self.linker, self.offset = BoxLinker(), int(found.warmup.people.tracks.max(initial=-1)) + 1
        self.frames, self.since = found.warmup.frames, 0
        self.used: dict[int, CameraEstimate] = {}
        self.history: list[dict] = [{"from_frame": 0, **found.estimate.summary()}]

    def step(self, process: Callable[[Frame], tuple[EnvironmentState, Frame]]
             ) -> Callable[[Frame], tuple[EnvironmentState, Frame]]:
        """``process`` with the camera in force given to each frame after the warm-up, its people kept."""

        def refined(frame: Frame) -> tuple[EnvironmentState, Frame]:
            after = frame.index >= self.found.warmup.frames
            if after and self.camera is not None:
                frame = dataclasses.replace(frame, camera=self.camera)
            state, frame = process(frame)
            self.used[frame.index] = self.estimate
            if after and frame.detections is not None:
                self._keep(frame)
            return state, frame

        return refined

    def _keep(self, frame: Frame) -> None:
        assert frame.detections is not None
        self.since += 1
        if self.count >= REFINE_MAX_OBSERVATIONS:
            return
        people = observations_of(frame.detections, frame.index, self.linker(frame.detections.boxes) + self.offset)
        self.kept.append(people)
        self.count, self.frames = self.count + len(people), self.frames + 1
        if self.since >= REFINE_EVERY_FRAMES:
            self.since = 0
            self._refit(frame.index + 1)

    def _refit(self, start: int) -> None:
        from pedenv.calibration.refusals import CalibrationRefused

        people = Observations.concat(self.kept)
        self.kept = [people]
        seen = WarmUp(people, self.frames, self.found.warmup.image)
        try:
            estimate = estimate_from(seen, self.found.backend_name, self.found.intrinsics, static=True)
        except CalibrationRefused as exc:
            self.history.append({"from_frame": start, "refused": str(exc), "observations": len(people)})
            return
        self.estimate, self.camera = estimate, estimate.camera(self.found.mount)
        self.history.append({"from_frame": start, **estimate.summary()})

    def widened(self, write: Callable[[tuple[EnvironmentState, Frame]], None]
                ) -> Callable[[tuple[EnvironmentState, Frame]], None]:
        """``write`` given each state widened by the estimate its frame ran with."""
        from pedenv.calibration.spread import widen_state

        def widened_write(result: tuple[EnvironmentState, Frame]) -> None:
            estimate = self.used.pop(result[1].index, self.estimate)
            write((widen_state(result[0], estimate, result[1].ego), result[1]))

        return widened_write

    def finish(self, folder: Path, summary: dict) -> None:
        """The last estimate's files into the run's ``folder`` (over the warm-up's) and into
        ``summary`` (``run.json``'s ``calibration``, with ``refinements``: each estimate and the
        frame it applied from)."""
        seen = WarmUp(Observations.concat(self.kept), self.frames, self.found.warmup.image)
        final = write_estimate(folder, self.estimate, seen, self.found.backend_name, self.found.mount)
        final["refinements"] = self.history
        (folder / "calibration.json").write_text(json.dumps(final, indent=2, allow_nan=False) + "\n")
        summary["calibration"] = final
