"""Why LuGre is stability-bound for explicit methods: the Jacobian along a settled cycle.

The default scene with LuGre friction (A and B, 0.5 mm, omega = 2.5 pi), cycle 2 recorded at
4 000 points (DOP853, rtol 1e-6). At each point the Jacobian of the compiled right-hand side is
taken by central differences; printed: the percentiles of its spectral radius (1/s), the same
without the bristle states' own decay rates (the part ARK548 treats implicitly), the steps per
cycle that DOP853's real stability bound |h lambda| < 6 allows for each, and the steps DOP853
and ARK548 actually take on that cycle. Run: ``python benchmarks/lugre_stiffness.py`` (~20 s).
"""

from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
from _results import recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench.models import get_model
from workbench.solver import integrate

SCENE = Path(__file__).resolve().parents[1] / "studies" / "ninebar.toml"
STABILITY = 6.0  # DOP853's stability interval on the negative real axis, ~|h lambda| < 6


def main() -> None:
    base = workbench.load_scene(SCENE)
    scene = base.replace(effects={**base.effects, "friction": "lugre"})
    model = get_model(scene.model)
    params = scene.resolved_parameters
    prob = model.problem(params, scene.effects, scene.initial, ())
    period = model.forcing_period(params)
    t = np.linspace(period, 2 * period, 4001)
    res = integrate(prob, t, method="dop853", rtol=1e-6, atol=1e-6)
    hooks = importlib.import_module(prob.hooks)
    work = np.zeros(prob.work_size)
    n = prob.y0.size
    stiff = prob.stiff_states
    rho, rho_explicit = [], []
    for i in range(t.size):
        y, aux = res.Y[i], res.AUX[i]
        J = np.empty((n, n))
        for j in range(n):
            d = 1e-7 * max(abs(y[j]), prob.atol_scale[j])
            fp, fm = np.empty(n), np.empty(n)
            hooks.rhs(t[i], y + d * np.eye(n)[j], prob.p, prob.ip, aux.copy(), work, fp)
            hooks.rhs(t[i], y - d * np.eye(n)[j], prob.p, prob.ip, aux.copy(), work, fm)
            J[:, j] = (fp - fm) / (2 * d)
        rho.append(np.abs(np.linalg.eigvals(J)).max())
        J[stiff, stiff] = 0.0
        rho_explicit.append(np.abs(np.linalg.eigvals(J)).max())
    for name, r in (("full Jacobian", rho), ("without the bristle decay", rho_explicit)):
        r = np.array(r)
        pct = ", ".join(f"{v:.3g}" for v in np.percentile(r, [10, 50, 90, 99]))
        bound = period * np.mean(r / STABILITY)
        print(
            f"{name:26s} spectral radius 10/50/90/99 %: {pct} 1/s; "
            f"stability-bound DOP853 steps per cycle ~{bound:,.0f}"
        )
    for method in ("dop853", "ark548"):
        two = integrate(prob, np.array([0.0, 2 * period]), method=method, rtol=1e-6, atol=1e-6)
        one = integrate(prob, np.array([0.0, period]), method=method, rtol=1e-6, atol=1e-6)
        print(f"{method}: {two.stats['steps'] - one.stats['steps']:,} steps on cycle 2")


if __name__ == "__main__":
    with recording(__file__):
        main()
