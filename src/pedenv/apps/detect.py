"""``pedenv detect``: a pose backend over image files, their skeletons drawn and listed in JSON."""

from __future__ import annotations

from pathlib import Path

from pedenv.errors import InputError
from pedenv.images import read_image_rgb, write_image
from pedenv.outputs.detections import detections_to_dict, unique_names, write_detections
from pedenv.pose.tiling import CameraGeometry
from pedenv.visualize.overlay import draw_detections


def annotate_images(images, output: str | Path, backend, camera=None) -> Path:
    """Run a pose ``backend`` on image files; write ``output/detections.json`` and the drawn images.

    images: image paths. Each drawn image is ``output/<stem>_pose.png`` (``<stem>-2_pose.png``
    for a second image of the same name). The JSON (:mod:`pedenv.outputs.detections`) holds per
    image: file, width, height, backend, drawn image and persons. An image that cannot be
    read is listed under ``failed``; the others are still written, then an InputError names
    the failed ones. Returns the JSON path.
    ``camera``: a :class:`~pedenv.records.Camera` (``--calibration``) that places the ``far``
    band as ``pedenv run`` does (vehicle level); an image of another size than it is failed.
    """
    output = Path(output)
    paths = [Path(p) for p in images]
    if not paths:
        raise InputError("no images given")
    records, failed = [], []
    for path, name in zip(paths, unique_names(paths, "_pose.png")):
        try:
            image = read_image_rgb(path)
        except InputError as exc:
            failed.append({"file": str(path), "error": str(exc)})
            continue
        if camera is not None and (image.shape[1], image.shape[0]) != (camera.width, camera.height):
            failed.append({"file": str(path), "error": f"{path}: image is {image.shape[1]}x{image.shape[0]} px, the "
                                                      f"calibration says {camera.width}x{camera.height}"})
            continue
        det = backend.detect(image) if camera is None else backend.detect(image, CameraGeometry.of_camera(camera))
        drawn = write_image(output / name, draw_detections(image, det))
        records.append({"file": str(path), "width": image.shape[1], "height": image.shape[0],
                        "backend": backend.name, "drawn": str(drawn), "persons": detections_to_dict(det)})
    target = write_detections(output / "detections.json", records, failed)
    if failed:
        names = ", ".join(f["error"] for f in failed)
        raise InputError(f"{len(failed)} of {len(paths)} images could not be read ({names}); "
                         f"the detections of the other {len(records)} are in {target}")
    return target
