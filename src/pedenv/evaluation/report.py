"""Tables for the terminal: the paper's Table I and the ablation table, built with rich."""

from __future__ import annotations

from rich.table import Table

from pedenv.evaluation.metrics import Metrics


def fmt(x: float | None, digits: int) -> str:
    """A number for a table; "-" where there is none (None or NaN)."""
    return "-" if x is None or x != x else f"{x:.{digits}f}"


def results_table(metrics: Metrics, title: str = "") -> Table:
    """Absolute and relative error with counts, overall then per scene (Table I)."""
    table = Table(title=title or f"{metrics.info.get('dataset', '')} ({metrics.info.get('pose_backend', '')}, "
                                 f"{metrics.info.get('method', '')})")
    for col in ("Data", "Abs. error [m]", "Rel. error [%]", "# Pedestrians"):
        table.add_column(col, justify="left" if col == "Data" else "right")
    o = metrics.overall
    table.add_row("all", fmt(o.abs_error_m, 3), fmt(o.rel_error_pct, 2), str(o.count), style="bold")
    for name, s in metrics.scenes:
        table.add_row(name, fmt(s.abs_error_m, 3), fmt(s.rel_error_pct, 2), str(s.count))
    return table


def summary_lines(metrics: Metrics) -> list[str]:
    """Tracking quality, calibration and stage timings as short lines."""
    lines = []
    t = metrics.tracking
    if t:
        lines.append(f"tracking: MOTA {t['mota']:.3f}  IDF1 {t['idf1']:.3f}  ID switches {t['id_switches']}")
    c = metrics.calibration
    if c.get("within_1sigma") == c.get("within_1sigma"):
        lines.append(f"uncertainty: {100 * c['within_1sigma']:.1f} % of errors within 1 sigma (ideal 39.3), "
                     f"{100 * c['within_2sigma']:.1f} % within 2 sigma (ideal 86.5), "
                     f"mean NEES {c.get('mean_nees', float('nan')):.2f} (ideal 2)")
    tm = metrics.timing_ms
    lines.append(f"runtime: tracking {tm['tracking_per_frame']:.3f} ms/frame (paper 0.35), "
                 f"position {tm['position_per_pedestrian']:.3f} ms/pedestrian (paper 0.29)")
    return lines


def comparison_table(rows: list[tuple[str, Metrics]], title: str) -> Table:
    """One row per variant (ablation or method): overall errors and counts."""
    table = Table(title=title)
    for col in ("Variant", "Abs. error [m]", "Rel. error [%]", "# Pedestrians"):
        table.add_column(col, justify="left" if col == "Variant" else "right")
    for name, m in rows:
        o = m.overall
        table.add_row(name, fmt(o.abs_error_m, 3), fmt(o.rel_error_pct, 2), str(o.count))
    return table
