"""The flutter of a study's sliding contact: the Jacobian's eigenvalues against the friction
coefficient, and the onset where the sliding mode grows within a crank cycle."""

from __future__ import annotations

import math

import numpy as np

from workbench.study._spec import Study

__all__ = ["flutter"]

FLUTTER_SAMPLES = 200
FLUTTER_CYCLES = 1


def flutter(study: Study, quick: bool) -> dict | None:
    """The flutter of the sliding contact against the friction coefficient: for every value of
    each ``[flutter]`` case's sweep, the eigenvalues of the rhs Jacobian
    (:func:`workbench.analysis.jacobian_spectrum`) at the records where both journals are in
    contact, over one crank cycle after the transient (200 records). Per value: the median and
    90th percentile of the largest real part (s-1), the frequency (Hz) at the largest, and the
    fraction of records in continuous contact. The onset is where the median first exceeds the
    crank frequency (the sliding mode then grows e-fold within a crank cycle), interpolated."""
    if not study.flutter:
        return None
    from workbench import analysis

    spec = dict(study.flutter)
    param = spec["parameter"]
    out = {**spec, "status": "computed", "cases": {}}
    for case in spec["cases"]:
        scene = study.cases[case]
        values = list(scene.sweep[param])
        if quick:
            values = values[:: max(1, len(values) // 3)]
        rows = {"values": values, "median": [], "p90": [], "frequency": [], "fraction": []}
        omega = float(scene.resolved_parameters["omega"])
        for v in values:
            point = scene.with_parameters(**{param: v}).replace(
                run={"cycles": FLUTTER_CYCLES, "transient_cycles": scene.run["transient_cycles"]},
                record={"samples_per_period": FLUTTER_SAMPLES},
            )
            r = analysis.jacobian_spectrum(point)
            both = [i for i, m in enumerate(r.modes.values) if m.count("contact") == 2]
            sel = np.isin(r.mode.values, both)
            top = r.largest_real.values[sel]
            rows["fraction"].append(float(sel.mean()))
            if top.size:
                i = int(np.argmax(top))
                rows["median"].append(float(np.median(top)))
                rows["p90"].append(float(np.quantile(top, 0.9)))
                rows["frequency"].append(float(r.frequency.values[sel][i]))
            else:
                rows["median"].append(math.nan)
                rows["p90"].append(math.nan)
                rows["frequency"].append(math.nan)
        threshold = omega / (2 * math.pi)
        rows["threshold"] = threshold
        rows["onset"] = _first_crossing(values, rows["median"], threshold)
        out["cases"][case] = rows
    return out


def _first_crossing(x: list, y: list, level: float) -> float:
    """First x where y rises through ``level`` (linear interpolation; NaN if it never does)."""
    for i in range(1, len(x)):
        a, b = y[i - 1], y[i]
        if np.isfinite(a) and np.isfinite(b) and a < level <= b:
            return float(x[i - 1] + (level - a) / (b - a) * (x[i] - x[i - 1]))
    return math.nan
