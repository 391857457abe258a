"""The ``onnx`` backend: a YOLO-pose ONNX model on onnxruntime, numpy pre/post-processing.

No torch needed at run time. The model comes from ``pedenv models prepare`` (one export
with a dynamic input shape) or from any compatible file (input (1, 3, H, W), output (1, 56, N)).
Detection modes (:mod:`pedenv.pose.tiling`): ``fast`` is one pass with the input fitted to
the frame's aspect; ``far`` adds tiles over the band where far people stand.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pedenv.errors import InputError, require_extra
from pedenv.pose import models
from pedenv.pose.levels import plan_passes
from pedenv.pose.merge import MergeConfig
from pedenv.pose.multipass import detect_levels
from pedenv.pose.postprocess import decode, frame_image, letterbox, parse_input_size, to_input_tensor
from pedenv.pose.tiling import CameraGeometry, DetectionConfig, Pass
from pedenv.records import Detections, Frame


def _check_unit(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value <= 1.0:
        raise InputError(f"{name} must be in [0, 1], got {value!r}")
    return float(value)


class OnnxPose:
    """YOLO-pose on onnxruntime.

    model_path: an ONNX file; None takes the cached model (a fixed export for ``input_size``
        if one is cached, else the dynamic one).
    input_size: network input, ``640`` or ``"384x640"`` / ``(384, 640)`` (height x width);
        must match a model with a fixed input. Given without ``detection``: one pass at this
        size (the behaviour before detection modes). With ``detection``: the whole-frame pass's input.
    detection: ``"fast"``, ``"far"`` or a :class:`DetectionConfig`; None means ``"far"``
        unless ``input_size`` is given. A model with a fixed input runs every pass at that size.
    merge: how the passes' detections are merged (:class:`MergeConfig`; None: its defaults).
    score_threshold: persons scoring at or below this are dropped (0.25). Raising it
        keeps fewer, surer persons.
    iou_threshold: a box overlapping a higher-scoring one by more than this IoU is
        suppressed (0.7). Lowering it merges nearby persons more readily.
    max_detections: at most this many persons per image (300).
    threads: onnxruntime intra-op threads (1..64; 2 suits a 2-core machine).
    spin_wait: let onnxruntime's idle threads spin for work (False). Spinning saves a little
        on an otherwise idle machine; on a busy one (the tracker, other processes) it burns
        the cores the network needs: a 384x640 pass took twice as long with it at load 19
        on 2 cores (median 767 vs 372 ms).
    """

    name = "onnx"

    def __init__(self, model_path: str | Path | None = None, input_size=None, score_threshold: float = 0.25,
                 iou_threshold: float = 0.7, max_detections: int = 300, threads: int = 2,
                 detection: str | DetectionConfig | None = None, spin_wait: bool = False,
                 merge: MergeConfig | None = None) -> None:
        require_extra("onnxruntime", "pose", "the onnx pose backend")
        import onnxruntime as ort

        self.score_threshold = _check_unit("score_threshold", score_threshold)
        self.iou_threshold = _check_unit("iou_threshold", iou_threshold)
        if isinstance(max_detections, bool) or not isinstance(max_detections, int) or max_detections < 1:
            raise InputError(f"max_detections must be an integer >= 1, got {max_detections!r}")
        if isinstance(threads, bool) or not isinstance(threads, int) or not 1 <= threads <= 64:
            raise InputError(f"threads must be an integer in [1, 64], got {threads!r}")
        self.max_detections = max_detections
        self.threads = threads
        wanted = None if input_size is None else parse_input_size(input_size)
        if detection is None and wanted is None:
            detection = "far"
        if isinstance(detection, str):
            detection = DetectionConfig.named(detection)
        elif detection is not None and not isinstance(detection, DetectionConfig):
            raise ValueError(f"detection must be 'fast', 'far' or a DetectionConfig, got {detection!r}")
        self.detection: DetectionConfig | None = detection
        self.merge = MergeConfig() if merge is None else merge
        if model_path is None:
            model_path = models.find_onnx_model(wanted)
        self.model_path = Path(model_path).expanduser()
        if not self.model_path.is_file():
            raise InputError(f"{self.model_path}: ONNX model file not found")
        options = ort.SessionOptions()
        options.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
        options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
        options.intra_op_num_threads = threads
        options.inter_op_num_threads = 1
        options.log_severity_level = 3
        options.add_session_config_entry("session.intra_op.allow_spinning", "1" if spin_wait else "0")
        try:
            self._session = ort.InferenceSession(str(self.model_path), options, providers=["CPUExecutionProvider"])
        except Exception as exc:
            raise InputError(f"{self.model_path}: not a readable ONNX model: {exc}") from None
        fixed = models.check_session(self._session, self.model_path)
        self.dynamic = None in fixed
        self._base_input = wanted
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
        #: The passes the last :meth:`detect` ran, and how their rows were chosen.
        self.last_passes: list[Pass] = []
        self.last_note = ""

    def __call__(self, frame: Frame) -> Detections:
        return self.detect(frame_image(frame), CameraGeometry.from_frame(frame))

    def _infer(self, tensor: np.ndarray) -> np.ndarray:
        return self._session.run(None, {self._input_name: tensor})[0]

    def plan(self, width: int, height: int, geometry: CameraGeometry | None = None) -> tuple[list[Pass], str]:
        """The passes this backend runs on a ``width`` x ``height`` image before any detection,
        and how they were chosen (levels whose rows wait for a fit to the people found are
        only named in the note; :attr:`last_passes` holds what :meth:`detect` ran)."""
        if self.detection is None:
            raise InputError(f"{self.model_path}: no detection mode set (one pass at {self.input_size}): "
                             "nothing to plan")
        passes, note = plan_passes(width, height, self.detection, geometry)
        if self._base_input is not None:
            passes[0] = Pass(passes[0].region, self._base_input, "full")
        return passes, note

    def detect(self, image_rgb: np.ndarray, geometry: CameraGeometry | None = None) -> Detections:
        """2D skeletons in ``image_rgb`` (H, W, 3) uint8 RGB; pixels of that image.

        geometry: the camera's intrinsics, tilt and height for the ``far`` band; None (no
        calibration) tiles the whole image.
        """
        if self.detection is None:
            padded, box = letterbox(image_rgb, self.input_size)
            self.last_passes = [Pass((0, 0, image_rgb.shape[1], image_rgb.shape[0]), self.input_size, "full")]
            return decode(self._infer(to_input_tensor(padded)), box, self.score_threshold, self.iou_threshold,
                          self.max_detections)
        dets, self.last_passes, self.last_note = detect_levels(
            self._infer, image_rgb, self.detection, geometry, fixed_input=None if self.dynamic else self.input_size,
            score_threshold=self.score_threshold, iou_threshold=self.iou_threshold,
            max_detections=self.max_detections, base_input=self._base_input, merge=self.merge)
        return dets

    def describe(self) -> dict:
        """What to save next to results: backend, model file, input size, detection mode, thresholds."""
        return {"backend": self.name, "model": str(self.model_path), "input_size": list(self.input_size),
                "detection": None if self.detection is None else self.detection.to_dict(),
                "score_threshold": self.score_threshold, "iou_threshold": self.iou_threshold}
