"""The step's error as the largest of its blocks' scaled RMS errors
(:attr:`workbench.solver.Problem.error_blocks`; issue 39 item 3): states that a derived system
adds beside the model's own (tangent vectors, accumulators) must not dilute the model's error
estimate, as CVODES keeps each sensitivity's error apart (Serban & Hindmarsh 2005)."""

import numpy as np
import pytest

from workbench import load_scene
from workbench.models import get_model
from workbench.solver import Problem, integrate
from workbench.solver._loop_types import DOP853, DOPRI5
from workbench.solver._numerics import error_norm
from workbench.solver._radau import scaled_rms
from workbench.solver._tableaux import DOP853_E3, DOP853_E5, RK45_E
from workbench.solver._tangent import state_scale, tangent_problem

RTOL = 1e-6


def _synthetic(n: int, rng):
    K = rng.standard_normal((13, n))
    y, y_new = rng.standard_normal(n), rng.standard_normal(n)
    atol = np.full(n, 1e-6)
    return K, y, y_new, atol


def _rms_by_hand(method, K, h, y, y_new, atol, idx):
    """The norm of Hairer et al. (1993, II.4.11; DOP853's 5th/3rd-order blend) over the states
    ``idx``, written out with numpy."""
    sc = atol[idx] + RTOL * np.maximum(abs(y[idx]), abs(y_new[idx]))
    if method == DOP853:
        e5 = ((DOP853_E5 @ K[:, idx]) / sc) ** 2
        e3 = ((DOP853_E3 @ K[:, idx]) / sc) ** 2
        return abs(h) * e5.sum() / np.sqrt((e5.sum() + 0.01 * e3.sum()) * idx.size)
    e = h * (RK45_E @ K[: RK45_E.size, idx]) / sc
    return np.sqrt(np.mean(e**2))


@pytest.mark.parametrize("method", [DOP853, DOPRI5])
def test_the_error_is_the_largest_blocks(method):
    rng = np.random.default_rng(1)
    n, h = 10, 1e-3
    K, y, y_new, atol = _synthetic(n, rng)
    K[:, 4:] *= 1e-3  # a quiet second block
    one = np.array([0, n], dtype=np.int64)
    two = np.array([0, 4, n], dtype=np.int64)
    empty = np.zeros(0, np.int64)
    args = (method, K, h, y, y_new, RTOL, atol, empty, np.zeros(0))
    whole = _rms_by_hand(method, K, h, y, y_new, atol, np.arange(n))
    first = _rms_by_hand(method, K, h, y, y_new, atol, np.arange(4))
    assert error_norm(*args, one) == pytest.approx(whole, rel=1e-12)
    assert error_norm(*args, two) == pytest.approx(first, rel=1e-12)
    # the quiet block dilutes the first one's error in the one-block norm by about sqrt(4/10)
    assert error_norm(*args, one) < 0.7 * error_norm(*args, two)


def test_the_implicit_methods_error_is_the_largest_blocks_too():
    rng = np.random.default_rng(2)
    e, y, y_new = rng.standard_normal(6), rng.standard_normal(6), rng.standard_normal(6)
    e[2:] = 0.0
    atol = np.full(6, 1e-6)
    sc = atol + RTOL * np.maximum(abs(y), abs(y_new))
    blocks = np.array([0, 2, 6], dtype=np.int64)
    assert scaled_rms(e, y, y_new, RTOL, atol, blocks) == pytest.approx(
        np.sqrt(np.mean((e[:2] / sc[:2]) ** 2)), rel=1e-12
    )
    assert scaled_rms(e, y, y_new, RTOL, atol, np.array([0, 6])) == pytest.approx(
        np.sqrt(np.mean((e / sc) ** 2)), rel=1e-12
    )
    e[4] = np.nan
    assert np.isnan(scaled_rms(e, y, y_new, RTOL, atol, blocks))


def test_blocks_must_partition_the_state():
    with pytest.raises(ValueError, match=r"error_blocks .* must rise strictly from 0 to the "):
        Problem(hooks="x", states=(), y0=np.zeros(3), p=np.zeros(0), error_blocks=[0, 2, 2, 3])
    with pytest.raises(ValueError, match="state's size 3"):
        Problem(hooks="x", states=(), y0=np.zeros(3), p=np.zeros(0), error_blocks=[0, 4])
    assert list(Problem(hooks="x", states=(), y0=np.zeros(3), p=np.zeros(0)).error_blocks) == [
        0,
        3,
    ]
    # a problem without states (a mechanism with ideal joints) has no block
    assert list(Problem(hooks="x", states=(), y0=np.zeros(0), p=np.zeros(0)).error_blocks) == [0]


def test_a_tangent_run_keeps_the_models_own_accuracy():
    """The Duffing oscillator with one tangent vector: the model's block alone must meet the
    tolerance, so the tangent run takes at least the model's own steps and its state is at
    least as accurate as the model's own run (against rtol 1e-12). With one norm over all its
    states (the model's 2, the vector's 2 and 7 accumulators that barely move) the tangent run
    took fewer steps than the model alone and its state was further off."""
    scene = load_scene({"model": {"name": "duffing"}})
    pb = get_model(scene.model).problem(scene.resolved_parameters, scene.effects, {}, ())
    t1 = np.array([40.0])
    bare = integrate(pb, t1, rtol=RTOL, atol=RTOL)
    exact = integrate(pb, t1, rtol=1e-12, atol=1e-12).Y[-1]
    V = np.zeros((pb.y0.size + pb.aux0.size, 1))
    V[0, 0] = state_scale(pb)[0]
    tp = tangent_problem(pb, V)
    assert list(tp.error_blocks) == [0, 2, 4, tp.y0.size]
    tan = integrate(tp, t1, rtol=RTOL, atol=RTOL)
    assert tan.status.name == "OK", tan.message
    assert tan.stats["steps"] >= bare.stats["steps"]
    err_bare = np.abs(bare.Y[-1] - exact).max()
    err_tan = np.abs(tan.Y[-1, :2] - exact).max()
    assert err_tan <= 1.5 * err_bare, (err_tan, err_bare)
