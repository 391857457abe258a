"""``stream`` detection: far-seeing over consecutive frames for about the cost of one pass.

The state a ``stream`` detector keeps between frames; each frame it is given the tracks the
model predicts (:class:`~pedenv.records.PredictedTracks`). Every frame: the whole-frame pass;
the live tracks it missed, in crops around their predicted boxes packed tallest first, about
ten to one packed input, twenty in a crowd (:mod:`pedenv.detection.packing`); the far band's
tiles in rotation, the oldest first (:mod:`pedenv.detection.budget`); the cascade's low-scoring
candidates in the room left in the packed inputs (:mod:`pedenv.detection.cascade`). A credit
bank (:class:`~pedenv.detection.budget.CreditBank`) lends a crowded frame what quiet frames
saved. A time step longer than ``max_gap_s`` (or backwards) or a new frame size restarts the
state; the first frame after a (re)start scans the whole band when ``cold_start``.
:attr:`StreamState.accounts` (saved in ``run.json``) says how the budget was spent.
"""

from __future__ import annotations

import math
from dataclasses import replace
from functools import partial

import numpy as np

from pedenv.boxes import iou_matrix
from pedenv.detection.accounts import StreamAccounts
from pedenv.detection.budget import CreditBank, FramePlan, band_tiles, plan_frame, tracks_at_risk
from pedenv.detection.cascade import candidate_placements, candidates, confirmed
from pedenv.detection.config import (
    CASCADE_MAX_ZOOM,
    CROWD_CROP,
    FIT_MIN_PEOPLE,
    FIT_MIN_SCORE,
    MERGE_SCALE_RATIO,
    STREAM_MISSED_IOU,
    TRACK_CROP,
    TRACK_MAX_SHIFT,
    DetectionConfig,
    RedetectConfig,
)
from pedenv.detection.geometry import CameraGeometry
from pedenv.detection.levels import HeightLine
from pedenv.detection.merge import merge_detections
from pedenv.detection.packing import Crop, crop_around, merge_crops, pack_tallest_first, packed_units, run_packed
from pedenv.detection.passes import run_level
from pedenv.detection.tiling import Pass, full_pass, units
from pedenv.detection.track_search import TrackFinder
from pedenv.pose.onnx_backend import OnnxPose
from pedenv.pose.postprocess import DecodeSettings
from pedenv.pose.providers import CPU
from pedenv.records import Detections, PredictedTracks

#: Crops and, per crop, the indices of the tracks (of those searched) it holds.
Grouped = tuple[list[Crop], list[list[int]]]
#: Boxes of the latest people found (all passes) kept to fit the band's rows without a calibration.
FIT_MEMORY = 60


class StreamState:
    """What ``stream`` remembers between frames, and the frame's passes (module doc).

    network: the pose network that runs the passes; config: a :class:`DetectionConfig` in mode
    ``stream``; decoding: the passes' score threshold, NMS and cut margin; match: the track
    search's matching (the run's ``redetect`` section).
    """

    def __init__(self, network: OnnxPose, config: DetectionConfig, decoding: DecodeSettings,
                 match: RedetectConfig) -> None:
        self.network, self.config, self.decoding, self.match = network, config, decoding, match
        self.accounts = StreamAccounts()
        #: Cut packed inputs to the room their crops use where that pays (:attr:`_trim`).
        self.trim = True
        self.last_passes: list[Pass] = []
        self.last_note = ""
        self._reset(None)

    @property
    def _trim(self) -> bool:
        """Whether packed inputs are cut to the room their crops use (a dynamic model, the CPU: on a
        GPU a pass costs about the same whatever its size, and every new input shape costs a session
        and cuDNN's set-up, :meth:`OnnxPose._session_for`). Measured on KITTI 0016: the tracks found
        for 1.77 units of packed inputs instead of 2.0 (``tests/detection/test_stream.py``)."""
        return self.trim and self.network.dynamic and self.network.provider == CPU

    def restart(self) -> None:
        """Forget the stream: the next frame is a first frame (a cold start)."""
        self._reset(None)

    def _reset(self, size: tuple[int, int] | None) -> None:
        self._size = size
        self._last_t: float | None = None
        self._tile_seen: dict[tuple[int, int], float] = {}
        self._fit_boxes = np.zeros((0, 4))
        self._dt = 0.1
        self.finder = TrackFinder(self.match)
        self.bank = CreditBank()
        self._untracked = np.zeros((0, 4))

    def _restart_if_needed(self, size: tuple[int, int], timestamp: float) -> bool:
        gap = None if self._last_t is None else timestamp - self._last_t
        restart = size != self._size or gap is None or not 0.0 < gap <= self.config.stream.max_gap_s
        if restart:
            if self._size is not None and self.accounts.frames:
                self.accounts.restarts += 1
            self._reset(size)
        else:
            assert gap is not None
            self._dt = 0.7 * self._dt + 0.3 * gap if self.accounts.frames else gap
        self._last_t = timestamp
        return restart

    def detect_frame(self, image: np.ndarray, geometry: CameraGeometry | None, timestamp: float,
                     tracks: PredictedTracks | None = None) -> Detections:
        """The persons in ``image`` (H, W, 3) uint8 RGB, px of that image, at ``timestamp`` s.

        tracks: the live tracks where the model expects them in this frame; None: no tracks.
        """
        b, cfg = self.network, self.config
        height, width = image.shape[:2]
        cold = self._restart_if_needed((height, width), float(timestamp)) and cfg.stream.cold_start
        first = full_pass(width, height, cfg)
        low: list[Detections] = []
        settings = self.decoding
        fixed = None if b.dynamic else b.input_size
        run = partial(run_level, b.infer_many, image, fixed_input=fixed, settings=settings,
                      low=low if cfg.cascade.enabled else None)
        parts = run([first])
        line = HeightLine.fit(self._fit_boxes, FIT_MIN_PEOPLE, height)
        tiles, note = band_tiles(width, height, cfg, geometry, line)
        tracks = tracks if tracks is not None else PredictedTracks.none()
        ids, predicted, hits = self._with_untracked(tracks.ids, tracks.boxes, tracks.hits)
        unseen = self.finder.unseen_s(ids, timestamp)
        known, last = self.finder.search_boxes(ids, predicted, TRACK_MAX_SHIFT)
        rows = tracks_at_risk(known, hits, unseen, parts[0][0].boxes, (height, width))
        early = (candidates(Detections.concat(low), parts[0][0]) if cfg.cascade.enabled
                 else Detections.empty())
        early_crops = candidate_placements(early, (height, width), cfg.stream.packed_size)
        ages = np.array([timestamp - self._tile_seen.get(t.key, -math.inf) for t in tiles])
        track_crops, plan = self._plan_tracks((known[rows], last[rows]), early_crops, (height, width),
                                              (units(first.input_size), np.array([t.units for t in tiles]), ages))
        held = [rows[group] for group in track_crops[1]]  # per crop, the tracks it holds
        chosen = list(range(len(tiles))) if cold else plan.tiles
        steps = [tiles[i].step for i in chosen]
        parts += run(steps)
        for i in chosen:
            self._tile_seen[tiles[i].key] = timestamp
        dets = parts[0][0] if len(parts) == 1 else merge_detections(parts, b.max_detections)
        extra, passes, found_tracks, verified = self._packed(image, dets, low, (known, last), held, track_crops,
                                                             plan.packed + (cfg.cascade.max_units if cold else 0),
                                                             settings)
        if len(extra):
            dets = merge_detections([(dets, np.zeros(len(dets), bool)), (extra, np.zeros(len(extra), bool))],
                                    b.max_detections)
        self.finder.update(ids, known, dets.boxes, timestamp, STREAM_MISSED_IOU)
        tracked = known[ids >= 0]
        free = iou_matrix(dets.boxes, tracked).max(axis=1) <= STREAM_MISSED_IOU if len(tracked) and len(dets) \
            else np.ones(len(dets), bool)
        self._untracked = dets.boxes[free]
        self._fit_boxes = np.concatenate([self._fit_boxes, dets.boxes[dets.scores >= FIT_MIN_SCORE]])[-FIT_MEMORY:]
        self.last_passes = [first, *steps, *passes]
        self.last_note = ("cold start, whole band; " if cold else "") + note
        if not cold:
            self.bank.charge(sum(units(p.input_size) for p in self.last_passes), cfg.stream)
        self.accounts.credit_units = self.bank.credit
        late = sum(1 for i, a in enumerate(ages) if i not in chosen and cfg.stream.scan_period_s < a < math.inf)
        self.accounts.add((first, steps, passes), plan, cold, (len(rows), found_tracks, verified), late)
        return dets

    def _plan_tracks(self, boxes: tuple[np.ndarray, np.ndarray], early_crops: list[Crop], image_size: tuple[int, int],
                     costs: tuple[float, np.ndarray, np.ndarray]) -> tuple[Grouped, FramePlan]:
        """The crops of the tracks to search (``boxes``: their search boxes and last detections,
        (K, 4) px each, most at risk first) and the frame's plan; ``costs``: the whole-frame
        pass's units, the band tiles' units and ages (s). The first of these the plan pays for
        in full: the usual crops, the usual crops with neighbours joined
        (:func:`~pedenv.detection.packing.merge_crops`), the crowd's smaller crops, those joined; per
        crop the rows of ``boxes`` it holds."""
        cfg = self.config
        packed = cfg.stream.packed_size
        searched, last = (np.asarray(b, float).reshape(-1, 4) for b in boxes)
        for person_px, margin, edge_px in (TRACK_CROP, CROWD_CROP):
            apart = [replace(crop_around(box, image_size, person_px, margin, CASCADE_MAX_ZOOM, packed, also),
                             edge_px=edge_px)
                     for box, also in zip(searched, last)]
            for crops, groups in self._arrangements(apart, crowd=person_px == CROWD_CROP[0]):
                needed = len({p.packed for p in pack_tallest_first(crops, packed)})
                with_cascade = pack_tallest_first(crops + early_crops, packed,
                                                  max_inputs=needed + cfg.cascade.max_units)
                wanted = max(needed, len({p.packed for p in with_cascade}))
                per_packed = packed_units(with_cascade, packed, self._trim)
                plan = plan_frame(costs[0], per_packed, wanted, costs[1], costs[2], self._dt, cfg.stream,
                                  self.bank.credit)
                if plan.packed >= needed:
                    return (crops, groups), plan
        return (crops, groups), plan

    def _arrangements(self, crops: list[Crop], crowd: bool) -> list[Grouped]:
        """The tracks' ``crops`` apart, or, the crowd's (``stream.merge_crops``), with neighbours
        joined unless that needs more packed inputs; per crop the indices of ``crops`` it holds."""
        apart = (crops, [[i] for i in range(len(crops))])
        if not crowd:
            return [apart]
        packed = self.config.stream.packed_size
        joined = merge_crops(crops, MERGE_SCALE_RATIO, packed)
        needed = [len({p.packed for p in pack_tallest_first(c, packed)}) for c in (joined[0], crops)]
        return [joined if needed[0] <= needed[1] else apart]

    def _with_untracked(self, ids: np.ndarray, predicted: np.ndarray,
                        hits: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The tracks and, after them, the persons found last frame that no track held (ids < 0)."""
        boxes = self._untracked
        if len(boxes) and len(predicted):
            boxes = boxes[iou_matrix(boxes, predicted).max(axis=1) <= STREAM_MISSED_IOU]
        if not len(boxes):
            return ids, predicted, hits
        return (np.concatenate([ids, -1 - np.arange(len(boxes))]), np.concatenate([predicted, boxes]),
                np.concatenate([hits, np.ones(len(boxes), np.int64)]))

    def _packed(self, image: np.ndarray, dets: Detections, low: list[Detections],
                boxes: tuple[np.ndarray, np.ndarray], rows: list[np.ndarray],
                track_crops: Grouped, limit: int,
                settings: DecodeSettings) -> tuple[Detections, list[Pass], int, int]:
        """At most ``limit`` packed inputs: the tracks' crops first, then the cascade's candidates
        in the room left (best score first). boxes: all tracks' search boxes and last detections
        ((T, 4) px each); rows: per crop of ``track_crops``, the rows of the tracks it holds."""
        cfg = self.config
        packed = cfg.stream.packed_size
        cands = candidates(Detections.concat(low), dets) if cfg.cascade.enabled else Detections.empty()
        cand_crops = candidate_placements(cands, (image.shape[0], image.shape[1]), packed)
        tracks = sorted(pack_tallest_first(track_crops[0], packed, max_inputs=limit), key=lambda p: p.item)
        placements = pack_tallest_first([p.crop for p in tracks] + cand_crops, packed, max_inputs=limit)
        if not placements:
            return Detections.empty(), [], 0, 0
        results, passes = run_packed(self.network.infer_many, image, placements, packed, settings, trim=self._trim)
        n = len(tracks)
        track_parts = [(int(row), r) for p, r in zip(placements, results) if p.item < n
                       for row in rows[tracks[p.item].item]]
        found = self.finder.pick(*boxes, [row for row, _ in track_parts], [r for _, r in track_parts])
        cand_parts = [(p, r) for p, r in zip(placements, results) if p.item >= n]
        verified = confirmed(cands, [p.item - n for p, _ in cand_parts], [p for p, _ in cand_parts],
                             [r for _, r in cand_parts])
        return Detections.concat([found, verified]), passes, len(found), len(verified)
