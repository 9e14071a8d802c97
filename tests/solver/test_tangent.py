"""The tangent system's two ways of carrying its vectors' sizes (issue 39: the tangent system near
its floor): normalised at the end of every step, the vectors following their linear equations in
between (the default), or continuously normalised by a rate in the equations."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from workbench import load_scene
from workbench.models import get_model
from workbench.solver import integrate
from workbench.solver._tangent import state_scale, tangent_columns, tangent_problem

ROOT = Path(__file__).resolve().parents[2]


def _problem(scene):
    scene = load_scene(scene)
    model = get_model(scene.model)
    return model.problem(scene.resolved_parameters, scene.effects, scene.initial, ())


def _flow_map(pb, t1, rtol, normalisation):
    n, na = pb.y0.size, pb.aux0.size
    s = state_scale(pb)
    V = np.zeros((n + na, n))
    V[:n] = np.diag(s)
    tp = tangent_problem(pb, V, normalisation=normalisation)
    res = integrate(tp, np.array([t1]), rtol=rtol, atol=rtol)
    assert res.status.name == "OK", res.message
    _, V, _ = tangent_columns(res.Y[-1], n, na, n)
    return V[:n] / s[None, :], res.stats


def test_normalisation_is_checked():
    pb = _problem({"model": {"name": "duffing"}})
    with pytest.raises(ValueError, match="normalisation='often': allowed 'step'"):
        tangent_problem(pb, np.eye(pb.y0.size + pb.aux0.size)[:, :1], normalisation="often")


def test_both_normalisations_give_one_tangent_map_through_impacts():
    """A free journal launched obliquely (impacts whose damping depends on the held onset
    velocity): the tangent map with the sizes taken out at every step's end equals the one
    continuously normalised, to the tolerance's order (rtol 1e-10: within 1e-6 of its largest
    entry)."""
    pb = _problem(
        {"model": {"name": "free_journal"}, "initial": {"vy": 0.2}, "run": {"duration": 0.01}}
    )
    M_step, stats = _flow_map(pb, 0.006, 1e-10, "step")
    M_cont, _ = _flow_map(pb, 0.006, 1e-10, "continuous")
    assert stats["events"] >= 4
    assert np.abs(M_step - M_cont).max() < 1e-6 * np.abs(M_cont).max()


def test_vectors_on_the_model_steps_cost_fewer_steps_than_continuous_normalisation():
    """The nine-bar's orbit in lasting contact at omega = 1.5 pi (Fig. 32's scene: c = 0.1 mm,
    c_f = 0.01), one cycle after 30, rtol 1e-6: continuously normalised, a direction's
    components other than its own rate move at the Jacobian's rates minus that rate, up to
    twice its spectral radius, and the steps follow (measured: 70 706 steps for four vectors,
    7 278 for one, where the model takes 3 082); normalised at the steps' ends the vectors'
    rates are the Jacobian's (7 471 and 6 637). A periodic orbit without events, so that
    another processor's rounding does not take the runs to other trajectories (over a chaotic
    window each vector's own error block made the two normalisations' counts differ by less
    than the windows' spread)."""
    scene = load_scene(ROOT / "studies/bifurcation_speed/sweep.toml").replace(sweep={})
    pb = _problem(scene.with_parameters(omega=1.5 * np.pi))
    period = 2.0 * np.pi / (1.5 * np.pi)
    t0 = 30 * period
    res = integrate(pb, np.array([t0]), rtol=1e-6, atol=1e-6)
    start = dataclasses.replace(pb, y0=res.Y[-1].copy(), aux0=res.AUX[-1].copy(), t0=t0)
    n, na = start.y0.size, start.aux0.size
    Q, _ = np.linalg.qr(np.random.default_rng(0).standard_normal((n, n)))
    t1 = np.array([t0 + period])
    plain = integrate(start, t1, rtol=1e-6, atol=1e-6).stats["steps"]
    steps = {}
    for m in (1, 4):
        V = np.zeros((n + na, m))
        V[:n] = state_scale(start)[:, None] * Q[:, :m]
        for how in ("step", "continuous"):
            tp = tangent_problem(start, V, reorthonormalise=10.0, normalisation=how)
            r = integrate(tp, t1, rtol=1e-6, atol=1e-6)
            assert r.status.name == "OK", r.message
            assert r.stats["events"] == 0  # the lasting contact: a smooth orbit
            steps[m, how] = r.stats["steps"]
    assert steps[4, "step"] < 0.2 * steps[4, "continuous"], (steps, plain)
    assert steps[1, "step"] < 0.95 * steps[1, "continuous"], (steps, plain)
