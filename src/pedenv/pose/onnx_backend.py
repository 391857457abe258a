"""The ``onnx`` backend: a YOLO-pose ONNX model on onnxruntime, numpy pre/post-processing.

No torch needed at run time. The model comes from ``pedenv models prepare`` (one export
with a dynamic input shape) or from any compatible file (input (1, 3, H, W), output (1, 56, N)).
This is the network only: one pass over a whole image, and the raw runs (:meth:`OnnxPose.infer_many`)
that the detection modes spend (``fast``, ``far``, ``stream``: :mod:`pedenv.detection`, whose
:class:`~pedenv.detection.detector.Detector` wraps this backend).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import fields, replace
from pathlib import Path
from queue import SimpleQueue
from typing import Any

import numpy as np

from pedenv.errors import InputError, require_extra
from pedenv.pose import models
from pedenv.pose.postprocess import (
    PAD_VALUE,
    DecodeSettings,
    decode,
    frame_image,
    letterbox,
    parse_input_size,
    to_input_tensor,
)
from pedenv.pose.providers import CPU, SessionConfig, create_session
from pedenv.records import Detections, Frame, PredictedTracks

#: At most this many sessions per backend on a GPU, one per input shape (:meth:`OnnxPose._session_for`);
#: each holds the model's weights (11 MB) and its own workspace.
MAX_GPU_SESSIONS = 24
#: On a GPU the first input shapes a backend meets run as they are, each in its own session: a
#: mode's passes over the whole frame and its bands recur every frame (far: 3 shapes, stream: up
#: to 4). Shapes met after these run padded to one of few shapes (:func:`gpu_input_shape`):
#: ``stream``'s crops and packed inputs in ``pedenv run`` vary from frame to frame (vtest.avi at
#: 1600x900: 192 px high, 128-608 px wide in 32 px steps, 17 shapes in 40 frames one by one, more
#: with the batch sizes), more than :data:`MAX_GPU_SESSIONS`, and each change of shape on a
#: shared session redoes the convolutions' cuDNN set-up. Padding every input cost ``far`` 1.4x on
#: its fixed bands (H200, docs/speed.md), hence the exact sessions first.
GPU_EXACT_SESSIONS = 8
#: The padding's step in height and width: in steps of 128 px the crops' widths take 5 values.
GPU_SHAPE_STEP_PX = 128


def gpu_input_shape(shape: tuple[int, ...], batch_dynamic: bool = True) -> tuple[int, ...]:
    """The (B, 3, H, W) shape an input of ``shape`` runs at on a GPU: H and W rounded up to
    :data:`GPU_SHAPE_STEP_PX`, B up to a power of two (kept when the model's batch axis is fixed)."""
    b, c, h, w = shape
    step = GPU_SHAPE_STEP_PX
    return ((1 << (b - 1).bit_length()) if batch_dynamic else b, c, -(-h // step) * step, -(-w // step) * step)


def pad_input(tensor: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """``tensor`` (B, 3, h, w) in a (B', 3, H', W') array of the letterbox's grey, at the top left."""
    b, _, h, w = tensor.shape
    out = np.full(shape, np.float32(PAD_VALUE / 255), np.float32)
    out[:b, :, :h, :w] = tensor
    return out


class OnnxPose:
    """YOLO-pose on onnxruntime.

    model_path: an ONNX file; None takes the cached model (a fixed export for ``input_size``
        if one is cached, else the dynamic one).
    input_size: network input, ``640`` or ``"384x640"`` / ``(384, 640)`` (height x width);
        must match a model with a fixed input; :meth:`detect` runs one pass at this size (None:
        640x640 on a dynamic model), a detection mode its whole-frame pass (:attr:`requested_input`).
        A model with a fixed input runs every pass at that size.
    decoding: ``score_threshold`` (0.25), ``iou_threshold`` (0.7) and ``max_detections`` (300)
        (:class:`~pedenv.pose.postprocess.DecodeSettings`); its fields may also be given as
        keywords (``OnnxPose(score_threshold=0.1)``).
    session: where and how the network runs (:class:`~pedenv.pose.providers.SessionConfig`:
        ``device`` auto/cpu/cuda, ``threads``, ``spin_wait``, ``batch``); its fields may also be
        given as keywords (``OnnxPose(device="cuda", threads=4)``). :attr:`provider` is the
        onnxruntime provider that runs it.
    """

    name = "onnx"

    def __init__(self, model_path: str | Path | None = None, input_size: int | str | Sequence[int] | None = None, *,
                 decoding: DecodeSettings | None = None, session: SessionConfig | None = None,
                 **options: Any) -> None:  # options: SessionConfig's and DecodeSettings' fields
        require_extra("onnxruntime", "pose", "the onnx pose backend")
        decode_names = {f.name for f in fields(DecodeSettings)} - {"edge_margin_px"}
        self.session_config = SessionConfig.of(session, {k: v for k, v in options.items() if k not in decode_names})
        self.threads = self.session_config.threads
        wanted = None if input_size is None else parse_input_size(input_size)
        #: The passes' decoding (score threshold, NMS, max persons, the cut margin at inner edges).
        self.decoding = replace(decoding or DecodeSettings(), **{k: v for k, v in options.items() if k in decode_names})
        if model_path is None:
            model_path = models.find_onnx_model(wanted)
        self.model_path = Path(model_path).expanduser()
        if not self.model_path.is_file():
            raise InputError(f"{self.model_path}: ONNX model file not found")
        self._session, self.provider = create_session(self.model_path, self.session_config)
        fixed = models.check_session(self._session, self.model_path)
        self.dynamic = None in fixed
        #: The input size asked for (None: none), the whole-frame pass's input in a detection mode.
        self.requested_input = wanted
        if self.dynamic:
            self.input_size = wanted or (640, 640)
        else:
            if wanted is not None and wanted != fixed:
                raise InputError(f"{self.model_path}: model input is {fixed[0]}x{fixed[1]}, "
                                 f"asked for {wanted[0]}x{wanted[1]}")
            height, width = fixed
            assert height is not None and width is not None  # not dynamic: both sides fixed
            self.input_size = (height, width)
        self._input_name = self._session.get_inputs()[0].name
        self._gpu_sessions: dict[tuple, Any] = {}  # input shape -> its session (GPU only: _session_for)
        self._side_sessions: SimpleQueue[Any] = SimpleQueue()  # free one-thread sessions (CPU: infer_many)
        self._side_pool: ThreadPoolExecutor | None = None
        self._batch_axis_dynamic = not isinstance(self._session.get_inputs()[0].shape[0], int)
        #: Seconds in the network's session runs and how many runs, since this backend was made.
        self.network_s, self.network_runs = 0.0, 0

    @property
    def score_threshold(self) -> float:
        return self.decoding.score_threshold

    @property
    def iou_threshold(self) -> float:
        return self.decoding.iou_threshold

    @property
    def max_detections(self) -> int:
        return self.decoding.max_detections

    def __call__(self, frame: Frame, tracks: PredictedTracks | None = None) -> Detections:  # noqa: ARG002 - one pass sees no tracks
        return self.detect(frame_image(frame))

    def infer(self, tensor: np.ndarray) -> np.ndarray:
        """The network on ``tensor`` (B, 3, h, w) float32, RGB in [0, 1] (letterboxed,
        :func:`~pedenv.pose.postprocess.to_input_tensor`); returns its raw output (B, 56, N)
        (:mod:`pedenv.pose.postprocess`; px of the input). On a GPU it may run padded to one of
        few shapes (:meth:`_gpu_input`): the same px, more (empty) output rows.
        Counted in :attr:`network_s` and :attr:`network_runs`."""
        start = time.perf_counter()
        n = tensor.shape[0]
        if self.provider != CPU and self.dynamic:
            tensor = self._gpu_input(tensor)
        out = self._session_for(tensor.shape).run(None, {self._input_name: tensor})[0][:n]
        self.network_s += time.perf_counter() - start
        self.network_runs += 1
        return out

    def _gpu_input(self, tensor: np.ndarray) -> np.ndarray:
        """``tensor`` as it runs on a GPU: as it is while its shape has a session or fewer than
        :data:`GPU_EXACT_SESSIONS` exist, else padded (:func:`gpu_input_shape`)."""
        shape = tuple(tensor.shape)
        if shape in self._gpu_sessions or len(self._gpu_sessions) < GPU_EXACT_SESSIONS:
            return tensor
        padded = gpu_input_shape(shape, self._batch_axis_dynamic)
        return tensor if padded == shape else pad_input(tensor, padded)

    def _session_for(self, shape: tuple) -> Any:
        """The session to run an input of ``shape`` in. On a GPU one session per input shape (at
        most :data:`MAX_GPU_SESSIONS`, then the first): the CUDA provider keeps each convolution's
        cuDNN set-up for the last shape it saw only, and redoing it for every change of shape (the
        whole frame, then tiles, then crops) cost far mode about 0.8 s per 1600x900 frame on an
        H100 (docs/speed.md). On the CPU one session serves every shape."""
        if self.provider == CPU:
            return self._session
        shape = tuple(shape)
        if shape not in self._gpu_sessions and len(self._gpu_sessions) < MAX_GPU_SESSIONS:
            self._gpu_sessions[shape] = self._session if not self._gpu_sessions else \
                create_session(self.model_path, self.session_config)[0]
        return self._gpu_sessions.get(shape, self._session)

    @property
    def batches(self) -> bool:
        """Whether :meth:`infer_batch` runs tensors of one size as one batch (``session.batch``;
        None: on a GPU only)."""
        batch = self.session_config.batch
        return self.provider != CPU if batch is None else batch

    @property
    def side_by_side(self) -> bool:
        """Whether :meth:`infer_many` runs several inputs side by side (the CPU, ``session.side_by_side``,
        more than one thread, no batching)."""
        return (self.provider == CPU and self.session_config.side_by_side and self.threads > 1
                and not self.batches)

    def infer_many(self, tensors: list[np.ndarray]) -> list[np.ndarray]:
        """The network on the independent inputs of one step (a level's tiles, packed inputs,
        crops): ``tensors`` (1, 3, h, w) float32 each, sizes may differ; one (1, 56, N) output
        each, in order, what :meth:`infer` gives one by one (side by side: to about 1e-4 px).
        On a GPU inputs of one size run as one batch (:meth:`infer_batch`); on the CPU side by
        side on one-thread sessions (:attr:`side_by_side`); else one after another."""
        if len(tensors) < 2:
            return [self.infer(t) for t in tensors]
        if self.batches:
            return self.infer_batch(tensors)
        if self.side_by_side:
            return self._infer_side_by_side(tensors)
        return [self.infer(t) for t in tensors]

    def _infer_side_by_side(self, tensors: list[np.ndarray]) -> list[np.ndarray]:
        """``tensors`` run on :attr:`threads` one-thread sessions at once, the largest first, each
        session taking the next input when it is free; counted in :attr:`network_s` as the
        group's wall time."""
        if self._side_pool is None:
            one = replace(self.session_config, threads=1)
            for _ in range(self.threads):
                self._side_sessions.put(create_session(self.model_path, one)[0])
            self._side_pool = ThreadPoolExecutor(max_workers=self.threads, thread_name_prefix="pedenv-pass")

        def run(tensor: np.ndarray) -> np.ndarray:
            session = self._side_sessions.get()
            try:
                return session.run(None, {self._input_name: tensor})[0]
            finally:
                self._side_sessions.put(session)

        start = time.perf_counter()
        largest_first = sorted(range(len(tensors)), key=lambda i: -tensors[i].size)  # the sessions end together
        futures = {i: self._side_pool.submit(run, tensors[i]) for i in largest_first}
        outputs = [futures[i].result() for i in range(len(tensors))]
        self.network_s += time.perf_counter() - start
        self.network_runs += len(tensors)
        return outputs

    def infer_batch(self, tensors: list[np.ndarray]) -> list[np.ndarray]:
        """The network on several inputs: ``tensors`` (1, 3, h, w) float32 each, sizes may differ;
        returns one (1, 56, N) output each, in order. Tensors of one size run as one batch when
        :attr:`batches` and the model's batch axis is dynamic, else one by one (same results)."""
        outputs: list[np.ndarray | None] = [None] * len(tensors)
        groups: dict[tuple, list[int]] = {}
        for i, tensor in enumerate(tensors):
            groups.setdefault(tuple(tensor.shape), []).append(i)
        for rows in groups.values():
            if len(rows) > 1 and self.batches and self._batch_axis_dynamic:
                out = self.infer(np.concatenate([tensors[i] for i in rows]))
                for k, i in enumerate(rows):
                    outputs[i] = out[k:k + 1]
            else:
                for i in rows:
                    outputs[i] = self.infer(tensors[i])
        return [o for o in outputs if o is not None]

    def detect(self, image_rgb: np.ndarray) -> Detections:
        """2D skeletons in ``image_rgb`` (H, W, 3) uint8 RGB, one pass at :attr:`input_size`; pixels of that image."""
        padded, box = letterbox(image_rgb, self.input_size)
        return decode(self.infer(to_input_tensor(padded)), box, self.score_threshold, self.iou_threshold,
                      self.max_detections)

    def describe(self) -> dict:
        """What to save next to results: backend, model file, input size, device, thresholds."""
        return {"backend": self.name, "model": str(self.model_path), "input_size": list(self.input_size),
                "device": self.session_config.device, "provider": self.provider, "side_by_side": self.side_by_side,
                "score_threshold": self.score_threshold, "iou_threshold": self.iou_threshold}
