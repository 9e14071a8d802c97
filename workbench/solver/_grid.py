"""Record grids: the exact times at which a run stores its state."""

from __future__ import annotations

import numpy as np

from workbench._scene import Scene


def record_grid(scene: Scene, t0: float, period: float | None) -> tuple[np.ndarray, dict]:
    """Record times (s) of a scene's run and the attributes that describe the grid.

    For a forced model the records lie at ``t0 + k T / samples_per_period`` for
    ``k = K0 .. K0 + cycles * samples_per_period`` (inclusive; ``K0 = transient_cycles *
    samples_per_period``), so every ``samples_per_period``-th record is a stroboscopic sample.
    Otherwise at ``t0 + transient + k dt`` up to ``transient + duration``.
    """
    run, rec = scene.run, scene.record
    attrs: dict = {}
    if period is not None and "cycles" in run:
        spp = rec.get("samples_per_period")
        if spp is None:
            spp = max(1, round(period / rec["dt"]))
        k0 = run["transient_cycles"] * spp
        k = np.arange(k0, k0 + run["cycles"] * spp + 1, dtype=np.float64)
        t = t0 + k * period / spp
        attrs.update(
            samples_per_period=int(spp),
            transient_cycles=run["transient_cycles"],
            cycles=run["cycles"],
        )
    else:
        if "samples_per_period" in rec and period is not None:
            dt = period / rec["samples_per_period"]
            attrs["samples_per_period"] = int(rec["samples_per_period"])
        else:
            dt = rec["dt"]
        n = int(np.floor(run["duration"] / dt * (1 + 1e-12))) + 1
        t = t0 + run["transient"] + np.arange(n) * dt
        attrs.update(record_dt=dt, transient=run["transient"])
    return t, attrs
