"""Where the pose network runs: the ``device`` option and onnxruntime's execution providers.

``device``: ``"auto"`` takes TensorRT (where its libraries are installed), else CUDA, else the
CPU, whichever onnxruntime offers and can start; ``"cpu"`` the CPU only; ``"cuda"`` a GPU or one
clear error (the user asked for it). The GPU build of onnxruntime comes with the ``gpu`` extra
(``pip install -e ".[gpu]"``: ``onnxruntime-gpu`` with the CUDA and cuDNN libraries as pip
packages, no system CUDA); :func:`create_session` loads those libraries first
(``onnxruntime.preload_dlls``). onnxruntime falls back to the CPU silently when a GPU provider
cannot start; the providers the session really holds are what :func:`create_session` returns.
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING

from pedenv.errors import InputError
from pedenv.pose.models import cache_dir
from pedenv.validation import check_bool, check_choice, check_count

if TYPE_CHECKING:
    import onnxruntime as ort

#: The valid values of ``device``.
DEVICES = ("auto", "cpu", "cuda")
CPU, CUDA, TENSORRT = "CPUExecutionProvider", "CUDAExecutionProvider", "TensorrtExecutionProvider"
GPU_HINT = ('it needs an NVIDIA GPU with its driver and the gpu extra (pip uninstall onnxruntime; '
            'pip install -e ".[gpu]"), or --device auto or cpu')


def check_device(device: object) -> str:
    """``device`` when it is one of :data:`DEVICES`, else one InputError naming them."""
    if not isinstance(device, str) or device not in DEVICES:
        raise InputError(f"device must be one of {', '.join(DEVICES)}, got {device!r}")
    return device


@dataclass(frozen=True)
class SessionConfig:
    """How the onnxruntime session runs.

    device: ``auto``, ``cpu`` or ``cuda`` (module doc).
    threads: intra-op threads on the CPU (1..64; 2 suits a 2-core machine).
    spin_wait: let onnxruntime's idle threads spin for work (False). Spinning saves a little
        on an otherwise idle machine; on a busy one (the tracker, other processes) it burns
        the cores the network needs: a 384x640 pass took twice as long with it at load 19
        on 2 cores (median 767 vs 372 ms).
    batch: run the passes of one frame that share an input size as one batch; None (the
        default) batches on a GPU only (on a CPU a batch costs what its passes cost one by one).
    side_by_side: on the CPU, run the independent passes of one frame (a level's tiles, the
        packed inputs, the re-detection crops) side by side, each on its own session with one
        intra-op thread (``threads`` sessions), instead of one after another on ``threads``
        threads (True). The outputs agree to about 1e-4 px (onnxruntime splits some
        convolutions' sums differently by thread count); on 2 cores two one-thread passes
        side by side took 37 ms a 384x640 pass against 48 ms one after another with two threads
        (docs/speed.md, "Passes side by side").
    cudnn_search: how the CUDA provider picks each convolution's cuDNN algorithm: ``heuristic``
        (the default: cuDNN's own choice, no trial runs), ``exhaustive`` (onnxruntime's default:
        every algorithm tried) or ``default``. pedenv's passes change input size within a frame
        (whole frame, tiles, crops); with ``exhaustive`` each change re-ran the search: ``far``
        took about 5 s per 1600x900 frame on an H100 (docs/speed.md).
    """

    device: str = "auto"
    threads: int = 2
    spin_wait: bool = False
    batch: bool | None = None
    cudnn_search: str = "heuristic"
    side_by_side: bool = True

    def __post_init__(self) -> None:
        check_device(self.device)
        check_count("threads", self.threads, 1, 64)
        check_bool("spin_wait", self.spin_wait)
        if self.batch is not None:
            check_bool("batch", self.batch)
        check_choice("cudnn_search", self.cudnn_search, tuple(CUDNN_SEARCHES))
        check_bool("side_by_side", self.side_by_side)

    @classmethod
    def of(cls, session: SessionConfig | None, options: dict) -> SessionConfig:
        """``session`` (or the defaults) with the keyword ``options`` (``device=``, ``threads=`` ...) set."""
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(options) - set(names))
        if unknown:
            raise InputError(f"unknown onnx backend option(s) {', '.join(unknown)}; valid: {', '.join(names)}")
        base = session or cls()
        return cls(**{**{n: getattr(base, n) for n in names}, **options})


#: ``SessionConfig.cudnn_search`` -> the CUDA provider's ``cudnn_conv_algo_search``.
CUDNN_SEARCHES = {"heuristic": "HEURISTIC", "exhaustive": "EXHAUSTIVE", "default": "DEFAULT"}


def wanted_providers(device: str, available: list[str], trt_cache: Path | None = None,
                     cudnn_search: str = "heuristic") -> list:
    """The provider list to ask onnxruntime for, best first, given the ``available`` provider names.

    ``cuda`` without the CUDA provider raises InputError. TensorRT (``auto`` and ``cuda``, where
    available) caches its engines in ``trt_cache`` (one per input size; building one takes a while).
    """
    check_device(device)
    if device == "cpu":
        return [CPU]
    if CUDA not in available:
        if device == "cuda":
            raise InputError(f"--device cuda: this onnxruntime has no CUDA provider (it offers "
                             f"{', '.join(available)}); {GPU_HINT}")
        return [CPU]
    providers: list = []
    if TENSORRT in available:
        options = {"trt_engine_cache_enable": True, "trt_engine_cache_path": str(trt_cache)} if trt_cache else {}
        providers.append((TENSORRT, options))
    return providers + [(CUDA, {"cudnn_conv_algo_search": CUDNN_SEARCHES[cudnn_search]}), CPU]


def create_session(model_path: Path,
                   config: SessionConfig) -> tuple[ort.InferenceSession, str]:  # onnxruntime: no stubs (Any)
    """An onnxruntime session for ``model_path`` run as ``config`` says, and the provider that
    runs it (the session's first provider, e.g. ``CPUExecutionProvider``).

    Raises InputError for a model onnxruntime cannot read, and for ``device="cuda"`` when no GPU
    provider started (no GPU, a driver too old, libraries missing: onnxruntime then falls back
    to the CPU on its own); ``auto`` then runs on the CPU.
    """
    import onnxruntime as ort

    options = ort.SessionOptions()
    options.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    options.intra_op_num_threads = config.threads
    options.inter_op_num_threads = 1
    options.log_severity_level = 3
    options.add_session_config_entry("session.intra_op.allow_spinning", "1" if config.spin_wait else "0")
    available = [p for p in ort.get_available_providers() if p != TENSORRT or _tensorrt_installed()]
    providers = wanted_providers(config.device, available, _trt_cache(), config.cudnn_search)
    if providers != [CPU] and hasattr(ort, "preload_dlls") and importlib.util.find_spec("nvidia") is not None:
        ort.preload_dlls()  # the CUDA and cuDNN libraries of the gpu extra's nvidia-* pip packages
    if providers != [CPU]:
        ort.set_default_logger_severity(4)  # a GPU that cannot start: auto takes the CPU, cuda says so below
    try:
        session = ort.InferenceSession(str(model_path), options, providers=providers)
    except Exception as exc:
        if providers != [CPU] and config.device == "auto":
            return create_session(model_path, replace(config, device="cpu"))  # a GPU that fails to start
        what = "not a readable ONNX model" + (", or the GPU session did not start" if providers != [CPU] else "")
        raise InputError(f"{model_path}: {what}: {exc}") from None
    finally:
        ort.set_default_logger_severity(3)
    running = list(session.get_providers())
    if config.device == "cuda" and CUDA not in running and TENSORRT not in running:
        raise InputError(f"--device cuda: onnxruntime could not start the CUDA provider (no usable GPU or "
                         f"CUDA libraries; it runs {', '.join(running)}); {GPU_HINT}")
    return session, running[0]


def _trt_cache() -> Path:
    return cache_dir() / "tensorrt"


def _tensorrt_installed() -> bool:
    """Whether TensorRT's libraries are at hand (its pip packages or a system libnvinfer)."""
    import ctypes.util

    return any(importlib.util.find_spec(m) is not None for m in ("tensorrt_libs", "tensorrt")) \
        or ctypes.util.find_library("nvinfer") is not None
