"""An animated bird's-eye view (``birds_eye.mp4``): every frame from above, drawn with OpenCV.

Seen in the ego vehicle's frame (x forward = up in the picture, y left = left), the ego at the
bottom centre: a grid every 5 m, the camera's field of view, the ego, each pedestrian's 2-sigma
ellipse, trail (the last ``trail`` positions of its track), velocity arrow (where it will be in
one second) and id, and the ground truth as black crosses with their ids where the frame is
labelled. One video for the whole run (or for the one ``scene`` named); trails start anew
with each scene, and the trail of a track not seen for ``trail`` frames is dropped, so the
memory stays bounded by the tracks of the last ``trail`` frames however long the stream.
"""

from __future__ import annotations

from collections import deque
from pathlib import Path

import cv2
import numpy as np

from pedenv.records import Frame
from pedenv.state import EnvironmentState
from pedenv.video_files import VideoOut
from pedenv.visualize.behaviour_drawing import draw_behaviour_birds_eye
from pedenv.visualize.overlay import ascii_text
from pedenv.visualize.shapes import covariance_ellipses, field_of_view

_BG, _GRID, _FOV = (250, 250, 250), (225, 225, 225), (250, 236, 218)
_EGO, _PED, _TRAIL, _TRUTH, _TEXT = (60, 160, 40), (40, 60, 220), (150, 160, 235), (20, 20, 20), (40, 40, 40)


class BirdsEyeVideo:
    """A :class:`pedenv.outputs.sinks.FrameSink` drawing each frame into an mp4 (OpenCV ``mp4v``).

    size_px: the square picture's side. ahead_m: metres shown ahead of the ego (the scale).
    trail: positions kept per track. fps: the video's rate; None takes it from the first two
    frames' timestamps (10 with a single frame). scene: draw only this scene's frames (None: all).
    """

    def __init__(self, path: str | Path, *, size_px: int = 640, ahead_m: float = 40.0, trail: int = 30,
                 fps: float | None = None, scene: str | None = None) -> None:
        if not 200 <= int(size_px) <= 4000:
            raise ValueError(f"size_px must be in [200, 4000], got {size_px}")
        if not 5.0 <= float(ahead_m) <= 500.0:
            raise ValueError(f"ahead_m must be in [5, 500] metres, got {ahead_m}")
        if not 1 <= int(trail) <= 10_000:
            raise ValueError(f"trail must be in [1, 10000] positions, got {trail}")
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.size, self.ahead, self.trail_length, self.fps = int(size_px), float(ahead_m), int(trail), fps
        self.only_scene = scene
        self.scale = 0.9 * self.size / self.ahead  # pixels per metre
        self.origin = np.array([self.size / 2.0, self.size * 0.95])  # the ego's pixel (u, v)
        self.frames_written = 0
        self._writer: VideoOut | None = None
        self._first: tuple[np.ndarray, float] | None = None
        self._scene: str | None = None
        self._base: tuple | None = None
        self._trails: dict[int, deque] = {}
        self._last_seen: dict[int, int] = {}  # track id -> the draw count when it was last seen
        self._draws = 0

    def write(self, state: EnvironmentState, frame: Frame | None = None) -> None:
        if self.only_scene is not None and state.scene != self.only_scene:
            return
        if state.scene != self._scene:
            self._scene = state.scene
            self._trails.clear()
            self._last_seen.clear()
        picture = self.draw(state, frame)
        if self._writer is None and self.fps is None and self._first is None:
            self._first = (picture, state.timestamp)  # the rate comes from the next frame
            return
        if self._writer is None:
            dt = state.timestamp - self._first[1] if self._first is not None else 0.0
            self._open(self.fps or (1.0 / dt if 0.0 < dt < 10.0 else 10.0))
            if self._first is not None:
                self._put(self._first[0])
                self._first = None
        self._put(picture)

    def close(self) -> None:
        if self._first is not None:
            self._open(self.fps or 10.0)
            self._put(self._first[0])
            self._first = None
        if self._writer is not None:
            self._writer.release()
            self._writer = None

    def draw(self, state: EnvironmentState, frame: Frame | None = None) -> np.ndarray:
        """The picture of one frame: (size, size, 3) uint8 BGR."""
        hfov = frame.camera.hfov if frame is not None else np.radians(64.5)
        cam_x = float(frame.camera.cam_to_vehicle[0, 3]) if frame is not None else 0.0
        img = self._background(round(hfov, 6), round(cam_x, 3)).copy()
        peds = state.pedestrians
        rot, origin = state.ego.rotation, state.ego.translation
        to_vehicle = lambda p: ((np.asarray(p, float) - origin) @ rot)[..., :2]  # noqa: E731
        self._update_trails(peds.track_ids, peds.positions)
        if len(peds):
            pos = to_vehicle(peds.positions)
            vel = peds.velocities[:, :2] @ rot[:2, :2]
            cov = np.einsum("ji,njk,kl->nil", rot[:2, :2], peds.covariances, rot[:2, :2])
            for ring in covariance_ellipses(pos, cov, sigma=2.0):
                cv2.polylines(img, [self._px(ring)], True, _PED, 1, cv2.LINE_AA)
            for tid in peds.track_ids:
                trail = self._trails[int(tid)]
                if len(trail) > 1:
                    cv2.polylines(img, [self._px(to_vehicle(np.array(trail)))], False, _TRAIL, 2, cv2.LINE_AA)
            for i, tid in enumerate(peds.track_ids):
                a, b = self._px(pos[i][None])[0], self._px((pos[i] + vel[i])[None])[0]
                cv2.arrowedLine(img, tuple(int(x) for x in a), tuple(int(x) for x in b), _PED, 2, cv2.LINE_AA,
                                tipLength=0.25)
                cv2.circle(img, tuple(int(x) for x in a), 5, _PED, -1, cv2.LINE_AA)
                cv2.putText(img, str(int(tid)), (int(a[0]) + 7, int(a[1]) - 7), cv2.FONT_HERSHEY_SIMPLEX, 0.45,
                            _PED, 1, cv2.LINE_AA)
        draw_behaviour_birds_eye(img, state, to_vehicle, self._px)  # heading, predicted path, conflict
        if frame is not None and frame.ground_truth is not None and len(frame.ground_truth):
            for gid, p in zip(frame.ground_truth.ids, self._px(to_vehicle(frame.ground_truth.positions))):
                cv2.drawMarker(img, (int(p[0]), int(p[1])), _TRUTH, cv2.MARKER_TILTED_CROSS, 10, 2, cv2.LINE_AA)
                cv2.putText(img, f"gt {int(gid)}", (int(p[0]) + 7, int(p[1]) + 14), cv2.FONT_HERSHEY_SIMPLEX, 0.35,
                            _TRUTH, 1, cv2.LINE_AA)
        cv2.rectangle(img, (0, 0), (self.size, 52), _BG, -1)
        title = (f"{ascii_text(state.scene)}  frame {state.frame_index}  t={state.timestamp:.2f} s  "
                 f"{len(peds)} pedestrians")
        cv2.putText(img, title, (10, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.55, _TEXT, 1, cv2.LINE_AA)
        cv2.putText(img, "red: pedenv (2-sigma, velocity, trail)   black x: ground truth   grid 5 m", (10, 44),
                    cv2.FONT_HERSHEY_SIMPLEX, 0.42, _TEXT, 1, cv2.LINE_AA)
        return img

    def _update_trails(self, track_ids: np.ndarray, positions: np.ndarray) -> None:
        """Append each track's position (``positions`` (N, 3), world frame, metres; ``track_ids`` (N,));
        drop the trails of tracks gone for ``trail`` frames."""
        self._draws += 1
        for tid, pos in zip(track_ids, positions):
            self._trails.setdefault(int(tid), deque(maxlen=self.trail_length)).append(np.asarray(pos, float))
            self._last_seen[int(tid)] = self._draws
        gone = [t for t, seen in self._last_seen.items() if self._draws - seen >= self.trail_length]
        for tid in gone:
            del self._trails[tid], self._last_seen[tid]

    @property
    def trails_kept(self) -> int:
        """How many tracks' trails are held (bounded: the tracks seen in the last ``trail`` frames)."""
        return len(self._trails)

    def _background(self, hfov: float, cam_x: float) -> np.ndarray:
        """Grid, field of view and ego: fixed in the vehicle frame, so drawn once per camera."""
        if self._base is None or self._base[0] != (hfov, cam_x):
            img = np.full((self.size, self.size, 3), _BG, np.uint8)
            self._grid(img)
            fov = field_of_view(hfov, self.ahead * 1.2) + [cam_x, 0.0]
            cv2.fillPoly(img, [self._px(fov)], _FOV, cv2.LINE_AA)
            ego = np.array([[2.0, 0.9], [2.0, -0.9], [-2.5, -0.9], [-2.5, 0.9]])
            cv2.fillPoly(img, [self._px(ego)], _EGO, cv2.LINE_AA)
            self._base = ((hfov, cam_x), img)
        return self._base[1]

    def _px(self, xy: np.ndarray) -> np.ndarray:
        """Vehicle-frame x-y (..., 2) metres -> integer pixels (..., 2), x forward = up."""
        xy = np.asarray(xy, float)
        u = self.origin[0] - xy[..., 1] * self.scale
        v = self.origin[1] - xy[..., 0] * self.scale
        return np.stack([u, v], axis=-1).round().astype(np.int32)

    def _grid(self, img: np.ndarray) -> None:
        side = self.ahead
        for m in np.arange(-side, side + 1e-9, 5.0):
            for line in (np.array([[m, -side], [m, side]]), np.array([[-side, m], [side, m]])):
                (u0, v0), (u1, v1) = self._px(line).tolist()
                cv2.line(img, (int(u0), int(v0)), (int(u1), int(v1)), _GRID, 1)

    def _open(self, fps: float) -> None:
        self._writer = VideoOut(self.path, fps, (self.size, self.size), what="bird's-eye video")

    def _put(self, picture: np.ndarray) -> None:
        assert self._writer is not None  # _open() came first
        self._writer.write(picture)
        self.frames_written += 1
