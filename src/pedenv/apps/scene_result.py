"""One scene of an evaluation as a unit of work, and the merge of scene results into metrics.

:func:`evaluate_scene` runs one scene through a fresh model and keeps everything the
metrics need (error samples, the scene's tracking accumulator, stage timings, its busiest
labelled frame, optionally its JSON Lines). :func:`merge_scene_results` turns the results,
in scene order, into the same :class:`~pedenv.evaluation.result.EvaluationResult` a serial
run over all scenes gives: the same numbers to the last digit, except the stage timings
(wall time, never the same twice). The serial run and the Ray executor both use these two.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from pedenv.behaviour.conflict import CONFLICT_PROBABILITY
from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.evaluation.behaviour import BehaviourRecorder, BehaviourSamples, behaviour_summary
from pedenv.evaluation.matching import match_one_to_one, match_to_ground_truth, position_errors
from pedenv.evaluation.metrics import ErrorSamples, Metrics
from pedenv.evaluation.result import EvaluationResult
from pedenv.evaluation.tracking_metrics import TrackingAccumulator
from pedenv.geometry import inverse_2x2
from pedenv.model import PedestrianEnvironmentModel
from pedenv.outputs.jsonl import environment_line
from pedenv.pose import PoseBackend
from pedenv.records import Frame
from pedenv.stage_timer import StageTimer
from pedenv.state import EnvironmentState

if TYPE_CHECKING:
    from pedenv.outputs.parquet import MatchesTableWriter

#: Tracks at least this many frames old count as settled in the busiest-frame choice (what the plot shows).
SETTLED_AGE = 3


@dataclass
class SceneResult:
    """What one scene contributes to an evaluation.

    samples: the matched pedestrians' errors. tracking: scene name -> motmetrics accumulator
    (empty without ground-truth ids). timer: the scene's stage wall times. frames: frames run.
    busiest: (state, frame) of the labelled frame with the most settled matched tracks, and
    that count (-1: no labelled frame). lines: the JSON Lines of every frame when collected.
    behaviour: the behaviour cues scored against the labelled future
    (:mod:`pedenv.evaluation.behaviour`; None without labelled frames).
    """

    name: str
    samples: ErrorSamples = field(default_factory=ErrorSamples)
    tracking: dict[str, Any] = field(default_factory=dict)
    timer: StageTimer = field(default_factory=StageTimer)
    frames: int = 0
    busiest: tuple[EnvironmentState, Frame] | None = None
    busiest_count: int = -1
    lines: list[str] | None = None
    behaviour: BehaviourSamples | None = None


@dataclass(frozen=True)
class SceneHooks:
    """What :func:`evaluate_scene` does beside scoring, all optional.

    on_frame(state, frame): after every frame (writers, sinks). pairs: a matched-pairs table
    writer. collect_lines: keep each frame's JSON Lines line in the result (for a worker whose
    files the caller writes). progress(frames_done): after every frame.
    """

    on_frame: Callable[[EnvironmentState, Frame], None] | None = None
    pairs: Any = None
    collect_lines: bool = False
    progress: Callable[[int], None] | None = None


def evaluate_scene(name: str, frames: Iterable[Frame], *, config: Config, backend: PoseBackend,
                   model_factory: Callable[[Config], PedestrianEnvironmentModel] = PedestrianEnvironmentModel,
                   hooks: SceneHooks | None = None) -> SceneResult:
    """Run scene ``name`` (its ``frames`` in time order) through a fresh model and score its labelled frames.

    ``hooks``: writers, a matched-pairs table, collected lines and progress (:class:`SceneHooks`).
    An InputError from a bad frame propagates; what ``hooks.on_frame`` wrote stays written.
    """
    hooks = hooks or SceneHooks()
    model = model_factory(config)
    tracking = TrackingAccumulator()
    behaviour = BehaviourRecorder(config.behaviour)
    result = SceneResult(name, timer=model.timer, lines=[] if hooks.collect_lines else None)
    for frame in frames:
        tracks = model.predict_tracks(frame)  # as pedenv.Pipeline: predict, detect with the tracks, update
        frame = replace(frame, detections=backend(frame, tracks))
        state = model.update(frame)
        if hooks.on_frame is not None:
            hooks.on_frame(state, frame)
        if result.lines is not None:
            result.lines.append(environment_line(state))
        if frame.ground_truth is not None:
            n = score_frame(frame, state, result.samples, tracking, hooks.pairs)
            behaviour.add(frame, state)
            if n > result.busiest_count:
                result.busiest, result.busiest_count = (state, frame), n
        result.frames += 1
        if hooks.progress is not None:
            hooks.progress(result.frames)
    result.tracking = dict(tracking.scenes)
    result.behaviour = behaviour.finish() if behaviour.pairs else None
    return result


def _behaviour(results: Sequence[SceneResult], threshold: float) -> dict | None:
    """``metrics.json``'s ``behaviour``: over all scenes, then per scene; None when nothing was scored."""
    scored = [(r.name, r.behaviour) for r in results if r.behaviour is not None]
    if not scored:
        return None
    summary = behaviour_summary([b for _, b in scored], threshold)
    summary["scenes"] = {name: behaviour_summary([b], threshold) for name, b in scored}
    return summary


def merge_scene_results(results: Sequence[SceneResult], info: dict,
                        conflict_threshold: float = CONFLICT_PROBABILITY) -> EvaluationResult:
    """The evaluation over ``results`` in their order (scene order), as one serial run gives it.

    Busiest frame: the first frame, in scene order, with the most settled tracks. Stage
    timings: the wall times summed over scenes, divided by the frames and pedestrians.
    ``conflict_threshold``: the conflict probability the behaviour figures flag at.
    """
    tracking = TrackingAccumulator()
    timer = StageTimer()
    busiest, busiest_count = None, -1
    for r in results:
        tracking.scenes.update(r.tracking)
        timer.tracking_s += r.timer.tracking_s
        timer.position_s += r.timer.position_s
        timer.frames += r.timer.frames
        timer.pedestrians += r.timer.pedestrians
        if r.busiest_count > busiest_count:
            busiest, busiest_count = r.busiest, r.busiest_count
    samples = {r.name: r.samples for r in results}
    metrics = Metrics.from_samples(samples, tracking.summary(), timer.per_stage_ms(), info,
                                   behaviour=_behaviour(results, conflict_threshold))
    return EvaluationResult(metrics, samples, busiest)


def score_frame(frame: Frame, state: EnvironmentState, samples: ErrorSamples, tracking: TrackingAccumulator,
                pairs: MatchesTableWriter | None = None) -> int:
    """Score one labelled frame (paper's matching); returns its count of settled matched tracks."""
    gt, peds = frame.ground_truth, state.pedestrians
    if gt is None:
        raise InputError(f"frame {frame.index} of {frame.scene}: no ground truth to score against")
    tracking.add(frame.scene, gt.ids, gt.boxes, peds.track_ids, peds.boxes)
    match = match_to_ground_truth(peds.boxes, peds.positions[:, :2], gt.boxes, gt.positions[:, :2])
    sel = match >= 0
    if sel.any():
        pred, truth = peds.positions[sel, :2], gt.positions[match[sel], :2]
        abs_err, rel_err, dist = position_errors(pred, truth, frame.ego.translation[:2])
        same = match_one_to_one(peds.boxes, gt.boxes)  # the covariances are judged against their own person
        own = same >= 0
        e = peds.positions[own, :2] - gt.positions[same[own], :2]
        cov = peds.covariances[own] + 1e-9 * np.eye(2)
        maha = np.sqrt(np.einsum("ni,nij,nj->n", e, inverse_2x2(cov), e))
        samples.add(abs_err, rel_err, dist, maha)
        if pairs is not None:
            pairs.write_pairs(frame, peds.track_ids[sel], gt.ids[match[sel]], pred, truth, abs_err, rel_err, dist)
    return int((sel & (peds.ages >= SETTLED_AGE)).sum())
