"""``pedenv detect``: a pose backend over image files, their skeletons drawn and listed in JSON."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

from pedenv.apps.output_safety import list_files, prepare_folder
from pedenv.detection.geometry import CameraGeometry
from pedenv.errors import InputError
from pedenv.images import image_size, read_image_rgb, write_image
from pedenv.outputs.detections import detections_to_dict, unique_names, write_detections
from pedenv.pose.base import PoseBackend
from pedenv.records import Camera
from pedenv.visualize.overlay import draw_detections


def annotate_images(images: Iterable[str | Path], output: str | Path, backend: PoseBackend, *,
                    camera: Camera | None = None, overwrite: bool = False,
                    prepare: bool = True, calibration: str | Path | None = None) -> Path:
    """Run a pose ``backend`` on image files; write ``output/detections.json`` and the drawn images.

    images: image paths. Each drawn image is ``output/<stem>_pose.png`` (``<stem>-2_pose.png``
    for a second image of the same name). The JSON (:mod:`pedenv.outputs.detections`) holds per
    image: file, width, height, backend, drawn image and persons. An image that cannot be
    read, is above the pixel limit or that the backend refuses (too small) is listed under
    ``failed`` with its error; the others are still processed and written, then one InputError
    names the failed files. Every image's header is read before ``output`` is prepared
    (``prepare``: :func:`~pedenv.outputs.output_dir.prepare_output_dir` with ``overwrite``),
    so when no image can be read an earlier run there is left as it was. Returns the JSON path.
    ``camera``: a :class:`~pedenv.records.Camera` (``--calibration``) that places the ``far``
    band as ``pedenv run`` does (vehicle level); an image of another size than it is failed.
    ``output`` may not be, hold or lie inside an image or ``calibration`` (its file), ``overwrite``
    or not (:func:`pedenv.apps.output_safety.prepare_folder`).
    """
    paths = [Path(p) for p in images]
    if not paths:
        raise InputError("no images given")
    failed = _unreadable(paths, output)
    if prepare:
        inputs = [("image", p) for p in paths] + [("--calibration", calibration)]
        output = prepare_folder(output, inputs, None, overwrite=overwrite, command="pedenv detect")
    output = Path(output)
    records = []
    for i, (path, name) in enumerate(zip(paths, unique_names(paths, "_pose.png"))):
        if i in failed:
            continue
        try:
            records.append(_annotate(path, output / name, backend, camera))
        except InputError as exc:
            message = str(exc)
            failed[i] = message if str(path) in message else f"{path}: {message}"
    target = write_detections(output / "detections.json", records,
                              [{"file": str(paths[i]), "error": failed[i]} for i in sorted(failed)])
    if prepare:
        list_files(output, "pedenv detect")  # what a later --overwrite may delete
    if failed:
        names = "; ".join(failed[i] for i in sorted(failed))
        raise InputError(f"{len(failed)} of {len(paths)} images could not be processed ({names}); "
                         f"the detections of the other {len(records)} are in {target}")
    return target


def _unreadable(paths: list[Path], output: str | Path) -> dict[int, str]:
    """index -> error of the images whose header cannot be read; InputError when none can."""
    failed: dict[int, str] = {}
    for i, path in enumerate(paths):
        try:
            image_size(path)
        except InputError as exc:
            failed[i] = str(exc)
    if len(failed) == len(paths):
        errors = failed[0] if len(paths) == 1 else \
            f"none of the {len(paths)} images can be read ({'; '.join(failed.values())})"
        raise InputError(f"{errors}; {output} was left as it was")
    return failed


def _annotate(path: Path, drawn_path: Path, backend: PoseBackend, camera: Camera | None) -> dict:
    """One image's record: read, detected (the far band placed by ``camera`` when given), drawn
    to ``drawn_path``."""
    # detect(image[, geometry]) is not in the PoseBackend protocol (only __call__ on a frame): the
    # image backends (Detector, OnnxPose, UltralyticsPose) have it, with the signatures of their own
    detector: Any = backend
    image = read_image_rgb(path)
    if camera is None:
        det = detector.detect(image)
    elif (image.shape[1], image.shape[0]) != (camera.width, camera.height):
        raise InputError(f"{path}: image is {image.shape[1]}x{image.shape[0]} px, the calibration says "
                         f"{camera.width}x{camera.height}")
    else:
        det = detector.detect(image, CameraGeometry.of_camera(camera))
    drawn = write_image(drawn_path, draw_detections(image, det))
    return {"file": str(path), "width": image.shape[1], "height": image.shape[0], "backend": backend.name,
            "drawn": str(drawn), "persons": detections_to_dict(det)}
