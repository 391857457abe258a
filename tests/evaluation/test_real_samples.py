"""The real network's detection cache (:mod:`pedenv.evaluation.real_samples`): one array per image
and field, named ``KEY|FIELD``, read back per image."""

import numpy as np

from pedenv.evaluation.real_samples import load_detection_cache


def test_the_cache_is_read_back_per_image_and_field(tmp_path):
    path = tmp_path / "det.npz"
    scores = np.array([0.9, 0.3], np.float32)
    np.savez_compressed(path, **{"kitti/0016/2|scores": scores, "kitti/0016/2|boxes": np.zeros((2, 4), np.float32),
                                 "nuscenes/CAM_FRONT|scores": np.zeros(0, np.float32),
                                 "_meta|mode": np.array(["far"])})
    cache = load_detection_cache(path)
    assert sorted(cache) == ["_meta", "kitti/0016/2", "nuscenes/CAM_FRONT"]
    np.testing.assert_array_equal(cache["kitti/0016/2"]["scores"], scores)
    assert cache["kitti/0016/2"]["boxes"].shape == (2, 4) and cache["_meta"]["mode"][0] == "far"
