"""The seeded end-to-end figures that ``tests/golden_metrics.json`` pins: which figures of an
evaluation are kept, and which differ from the file beyond their tolerance. ``tests/golden.py``
asserts them; ``benchmarks/golden_metrics.py`` computes, compares and rewrites the file."""

from __future__ import annotations

from pedenv.evaluation.metrics import Metrics

#: Absolute tolerance of each figure: errors in percentage points or metres, coverage and
#: tracking scores as fractions, counts exact.
TOLERANCE = {"rel_error_pct": 0.05, "abs_error_m": 0.01, "count": 0, "within_1sigma": 0.002,
             "within_2sigma": 0.002, "mean_nees": 0.01, "mota": 0.002, "idf1": 0.002, "id_switches": 0}


def figures(metrics: Metrics) -> dict:
    """The figures of one evaluation that the golden file keeps."""
    o, calibration, tracking = metrics.overall, metrics.calibration or {}, metrics.tracking or {}
    out = {"rel_error_pct": round(o.rel_error_pct, 3), "abs_error_m": round(o.abs_error_m, 4), "count": o.count}
    for key in ("within_1sigma", "within_2sigma", "mean_nees"):
        if key in calibration:
            out[key] = round(calibration[key], 4)
    for key in ("mota", "idf1", "id_switches"):
        if key in tracking:
            value = tracking[key]
            out[key] = int(value) if key == "id_switches" else round(float(value), 4)
    return out


def differences(measured: dict, golden: dict) -> list[str]:
    """Lines naming every figure outside its tolerance (or missing)."""
    bad = []
    for case, values in measured.items():
        for key, value in values.items():
            want = golden.get(case, {}).get(key)
            if want is None or abs(value - want) > TOLERANCE[key]:
                bad.append(f"{case} {key}: measured {value}, golden {want} (tolerance {TOLERANCE[key]})")
    return bad
