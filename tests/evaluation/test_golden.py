"""Which figures of an evaluation tests/golden_metrics.json keeps, and which differ beyond their
tolerance (:mod:`pedenv.evaluation.golden`)."""

from pedenv.evaluation.golden import TOLERANCE, differences, figures
from pedenv.evaluation.metrics import ErrorSummary, Metrics


def metrics() -> Metrics:
    overall = ErrorSummary(abs_error_m=2.71234, rel_error_pct=4.54321, count=812)
    return Metrics(overall=overall, scenes=[("scene", overall)], timing_ms={}, error_by_distance=[], info={},
                   calibration={"within_1sigma": 0.61912, "within_2sigma": 0.9261, "mean_nees": 1.2413},
                   tracking={"mota": 0.94123, "idf1": 0.86612, "id_switches": 233.0})


def test_the_kept_figures_are_rounded_and_the_id_switches_counted():
    assert figures(metrics()) == {"rel_error_pct": 4.543, "abs_error_m": 2.7123, "count": 812, "within_1sigma": 0.6191,
                                  "within_2sigma": 0.9261, "mean_nees": 1.2413, "mota": 0.9412, "idf1": 0.8661,
                                  "id_switches": 233}


def test_a_figure_inside_its_tolerance_passes_and_one_outside_or_missing_is_named():
    golden = {"case": figures(metrics())}
    near = {"case": {**golden["case"], "rel_error_pct": 4.543 + 0.9 * TOLERANCE["rel_error_pct"]}}
    assert differences(near, golden) == []
    far = {"case": {**golden["case"], "id_switches": 234}}
    assert differences(far, golden) == ["case id_switches: measured 234, golden 233 (tolerance 0)"]
    assert differences({"new": {"count": 3}}, golden) == ["new count: measured 3, golden None (tolerance 0)"]
