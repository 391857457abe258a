"""Where a static scene's paper-protocol mean comes from (:mod:`pedenv.evaluation.static_pairs`,
printed by benchmarks/static_cameras.py --breakdown --persons), on constructed matches."""

import numpy as np
import pytest

from pedenv.evaluation.static_pairs import breakdown, coverage_with_truth, persons

#: Per protocol pair: relative error %, the truth's range m, 1 for the estimate's own person, truth id.
PROTOCOL = np.array([[2.0, 10.0, 1, 7], [4.0, 20.0, 1, 8], [30.0, 10.0, 0, 7], [6.0, 40.0, 1, 9]])
#: Per one-to-one match: relative error %, truth id.
ONE_TO_ONE = np.array([[2.0, 7], [4.0, 8], [6.0, 9]])


def test_the_breakdown_splits_the_protocol_mean_into_its_groups():
    out = breakdown(PROTOCOL[:, :3])
    assert out["whole persons"] == [3, 4.0, 3.0]  # 3 pairs, mean 4 %, 12 of the 42 points over 4 pairs
    assert out["others"] == [1, 30.0, 7.5]
    assert out["whole persons"][2] + out["others"][2] == pytest.approx(PROTOCOL[:, 0].mean())
    assert out["0-15 m"] == [2, 16.0, 8.0] and out["30-1000 m"] == [1, 6.0, 1.5]


def test_persons_charge_each_fragment_to_the_person_it_was_scored_against():
    out = persons(ONE_TO_ONE, PROTOCOL, total=len(PROTOCOL))
    assert sorted(out) == [7, 8, 9]
    assert out[7]["one_to_one"] == [1, 2.0]
    assert out[7]["own"] == [1, 2.0, 0.5] and out[7]["others"] == [1, 30.0, 7.5]
    assert out[7]["range_m"] == 10.0 and out[9]["others"][0] == 0


def test_the_coverage_with_the_truths_uncertainty_counts_the_distances_inside_one_and_two_sigma():
    assert coverage_with_truth([np.array([0.5, 1.5]), np.array([2.5, 0.9])]) == {
        "within_1sigma_with_truth": 50.0, "within_2sigma_with_truth": 75.0}
    assert coverage_with_truth([]) == {}
