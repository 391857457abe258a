"""Reader of the per-camera JSON of shared/samples/real/nuscenes-0061."""

import json

import numpy as np
import pytest

from pedenv.datasets import nuscenes_cameras as nc
from pedenv.errors import InputError

from shared_paths import REAL_SAMPLES

ROOT = REAL_SAMPLES / "nuscenes-0061"


def test_five_cameras_nineteen_pedestrians():
    cameras = nc.read_cameras(ROOT)
    assert [c.camera for c in cameras] == ["CAM_BACK", "CAM_BACK_LEFT", "CAM_BACK_RIGHT", "CAM_FRONT_LEFT",
                                           "CAM_FRONT_RIGHT"]
    assert [len(c.pedestrians) for c in cameras] == [4, 2, 4, 1, 8]
    heights = np.concatenate([c.pedestrians.boxes[:, 3] - c.pedestrians.boxes[:, 1] for c in cameras])
    assert heights.min() == pytest.approx(38, abs=1) and heights.max() == pytest.approx(144, abs=1)
    assert all(c.image_path.is_file() and (c.width, c.height) == (1600, 900) for c in cameras)


def test_centres_project_into_their_boxes():
    for camera in nc.read_cameras(ROOT):
        peds = camera.pedestrians
        to_cam = np.linalg.inv(camera.cam_to_global)
        cam = (np.c_[peds.centers_global, np.ones(len(peds))] @ to_cam.T)[:, :3]
        assert np.allclose(cam, peds.centers_cam, atol=0.02)
        uv = cam @ camera.K.T
        uv = uv[:, :2] / uv[:, 2:]
        b = peds.boxes
        assert np.all((uv[:, 0] >= b[:, 0] - 1) & (uv[:, 0] <= b[:, 2] + 1) & (uv[:, 1] >= b[:, 1] - 1)
                      & (uv[:, 1] <= b[:, 3] + 1))
        assert np.allclose(camera.ego_to_global @ camera.cam_to_ego, camera.cam_to_global, atol=1e-4)


def test_missing_velocity_is_nan():
    back_left = nc.read_camera(ROOT / "CAM_BACK_LEFT.json")
    assert np.isnan(back_left.pedestrians.velocities_xy).all()
    assert np.all(back_left.pedestrians.ground_points_global[:, 2] < back_left.pedestrians.centers_global[:, 2])


@pytest.mark.parametrize("edit, message", [
    (lambda d: d.pop("K"), "missing key 'K'"),
    (lambda d: d.update(width=-3), "width must be a positive integer"),
    (lambda d: d.update(K=[[1, 0], [0, 1]]), "K must be a finite 3x3 matrix"),
    (lambda d: d["pedestrians"][0].pop("bbox_2d"), r"pedestrians\[0\]: missing or bad key 'bbox_2d'"),
    (lambda d: d["pedestrians"][0].update(bbox_2d=[1, 2, 3]), r"pedestrians\[0\]: boxes must be finite"),
])
def test_bad_json_names_the_file_and_key(tmp_path, edit, message):
    data = json.loads((ROOT / "CAM_BACK.json").read_text())
    edit(data)
    path = tmp_path / "CAM_BACK.json"
    path.write_text(json.dumps(data))
    (tmp_path / data.get("image", "x.jpg")).write_bytes(b"")
    with pytest.raises(InputError, match=message) as info:
        nc.read_camera(path)
    assert str(path) in str(info.value)
