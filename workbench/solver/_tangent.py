"""The tangent (variational) system of a problem, as a problem the compiled loop integrates.

See :mod:`workbench.solver._templates.tangent_hooks` for the equations (variational equations
between events, the saltation matrix at events, each tangent vector as a direction of unit size
and its log size) and the layout of the arrays built here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.solver._compile import tangent_for
from workbench.solver._problem import Problem
from workbench.solver._tangent_numerics import scratch_size

__all__ = [
    "N_META",
    "state_scale",
    "tangent_columns",
    "tangent_problem",
    "tangent_state",
    "tangent_growths",
    "tangent_volume",
    "tangent_weights",
]

N_META = 8


@dataclass(frozen=True)
class _State:
    """An internal state of a derived system (the solver's view of a declared state)."""

    name: str
    units: str = "1"
    long_name: str = ""


def state_scale(problem: Problem) -> np.ndarray:
    """Characteristic size of each state (state units): the problem's ``atol_scale`` where it is
    finite and positive, else 1. Tangent vectors are measured and orthonormalised in the state
    divided by this scale."""
    s = np.asarray(problem.atol_scale, dtype=float)
    return np.where(np.isfinite(s) & (s > 0), s, 1.0)


def tangent_weights(problem: Problem) -> np.ndarray:
    """Weights of the inner product in which tangent vectors of the extended state ``(y, aux)``
    are measured: ``1 / s^2`` per state (:func:`state_scale`) and ``1 / s_a^2`` per discrete
    state with a finite positive ``aux_scale`` (0 for the others, which the flow does not depend
    on: counters, records of the last event)."""
    sa = np.asarray(problem.aux_scale, dtype=float)
    wa = np.zeros(sa.size)
    ok = np.isfinite(sa) & (sa > 0)
    wa[ok] = 1.0 / sa[ok] ** 2
    return np.concatenate([1.0 / state_scale(problem) ** 2, wa])


def tangent_problem(
    problem: Problem,
    V: np.ndarray,
    *,
    time_scale: float = 1.0,
    log_det: float = 0.0,
    reorthonormalise: float | None = None,
    normalisation: str = "step",
) -> Problem:
    """The problem's state extended by the tangent vectors ``V`` (shape ``(n + na, m)``: state
    then discrete-state components, in their units) and the accumulated ``log |det S_yy|``.
    Each vector is carried as a direction of unit size (in the inner product of
    :func:`tangent_weights`) and its log size (read them with :func:`tangent_state`, the vectors
    with :func:`tangent_columns`, Benettin's accumulators with :func:`tangent_growths`).

    Parameters
    ----------
    problem : Problem
        The model's problem (its ``t0``, ``y0``, ``aux0`` are the start of the tangent run).
    V : ndarray
        Initial tangent vectors of the extended state ``(y, aux)``, one per column.
    time_scale : float
        A characteristic time of the model (s), which sizes the difference step in time of
        the event update and event function.
    log_det : float
        Initial value of the accumulated log volume change at events.
    reorthonormalise : float, optional
        Orthogonality defect (the columns' log sizes minus the log of the volume they span)
        beyond which the system re-orthonormalises its vectors by Gram-Schmidt at the end of
        an accepted step (or after an event's saltation), adding ``log R_kk`` to their log
        sizes (Benettin's accumulators), and integrates the log volume they span
        (:func:`tangent_volume`). Default None: never; the vectors stay ``Phi V`` (a monodromy
        matrix). Needs the compiled loop (its ``step_end`` hook).
    normalisation : {"step", "continuous"}
        How the vectors' sizes are taken out into their log sizes: "step" (default) at the
        end of every accepted step (the loop's ``step_end`` hook), the vectors following
        their linear equations in between; "continuous" by a rate in the equations (for a
        system integrated without the ``step_end`` hook, such as copies of this one side by
        side). See :mod:`workbench.solver._templates.tangent_hooks`.
    """
    n, na = problem.y0.size, problem.aux0.size
    V = np.asarray(V, dtype=float)
    if V.ndim != 2 or V.shape[0] != n + na:
        raise ValueError(
            f"tangent vectors must have shape (n + na, m) = ({n + na}, m); got {V.shape!r}"
        )
    m = V.shape[1]
    hooks = tangent_for(problem.hooks).__name__
    scale = state_scale(problem)
    w = tangent_weights(problem)
    # each column as a direction of unit size and its log size
    size = np.sqrt(np.einsum("j,jc,jc->c", w, V, V))
    size = np.where((size > 0) & np.isfinite(size), size, 1.0)
    U, log_size = V / size[None, :], np.log(size)
    states = tuple(problem.states) + tuple(
        _State(f"_tangent_{c}_{i}", "1", "tangent direction component")
        for c in range(m)
        for i in range(n + na)
    )
    states += (_State("_log_det_saltation", "1", "sum of log |det S_yy| at events"),)
    states += tuple(_State(f"_log_size_{c}", "1", "log size of tangent vector") for c in range(m))
    states += (
        _State("_log_volume", "1", "log volume spanned by the tangent vectors"),
        _State("_log_volume_memory", "1", "part of it fed back by the discrete state"),
        _State("_reorthonormalisations", "1", "re-orthonormalisations of the vectors"),
        _State("_log_volume_before", "1", "log volume taken out at steps' ends"),
        _State("_log_volume_memory_before", "1", "its memory part taken out at steps' ends"),
    )
    vscale = np.concatenate([scale, np.ones(na)])
    atol_scale = np.concatenate([scale, np.tile(vscale, m), np.ones(6 + m)])
    qr = reorthonormalise is not None
    if normalisation not in ("step", "continuous"):
        raise ValueError(
            f"normalisation={normalisation!r}: allowed 'step' (the default) or 'continuous'"
        )
    linear = normalisation == "step"
    if qr and not float(reorthonormalise) > 0:
        raise ValueError(
            f"reorthonormalise={reorthonormalise!r}: must be a positive orthogonality defect"
        )
    meta = [n, na, m, problem.event_direction.size, problem.p.size, problem.ip.size]
    meta += [problem.work_size, int(qr) | (2 if linear else 0)]  # flags
    return Problem(
        hooks=hooks,
        states=states,
        y0=np.concatenate([problem.y0, U.T.ravel(), [log_det], log_size, np.zeros(5)]),
        p=np.concatenate([problem.p, scale, w, [time_scale, float(reorthonormalise or 0.0)]]),
        ip=np.concatenate([problem.ip, np.array(meta, dtype=np.int64)]),
        aux0=problem.aux0,
        aux_scale=problem.aux_scale,
        event_direction=problem.event_direction,
        event_surface=problem.event_surface,
        atol_scale=atol_scale,
        t0=problem.t0,
        work_size=problem.work_size + scratch_size(n, na, m, problem.event_direction.size),
        failure=problem.failure,
        # the state's own blocks, then each tangent vector and the accumulators apart, so that
        # neither dilutes the state's error (nor one vector another's)
        error_blocks=np.concatenate(
            [problem.error_blocks, n + (n + na) * np.arange(1, m + 1), [len(states)]]
        ),
    )


def tangent_state(
    Y: np.ndarray, n: int, na: int, m: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Split a tangent-system state into the model state ``y``, the tangent directions ``U``
    (``(n + na, m)``, of about unit scaled size), their log sizes ``l`` (``(m,)``; the tangent
    vectors are ``U * exp(l)``, which can overflow after a long run) and the accumulated log
    volume change at events."""
    y = Y[:n]
    k = n + m * (n + na)
    U = Y[n:k].reshape(m, n + na).T
    return y, U, Y[k + 1 : k + 1 + m].copy(), float(Y[k])


def tangent_volume(Y: np.ndarray, n: int, na: int, m: int) -> tuple[float, float, int]:
    """With re-orthonormalisation: the log volume the tangent vectors span, since the start
    (its rate is the sum of their exponents), and the part of it that the discrete state fed
    back between events (see :mod:`workbench.solver._templates.tangent_hooks`; zeros without); and
    the number of re-orthonormalisations."""
    k = n + m * (n + na) + 1 + m
    return float(Y[k] + Y[k + 3]), float(Y[k + 1] + Y[k + 4]), int(Y[k + 2])


def tangent_growths(tangent: Problem, Y: np.ndarray) -> np.ndarray:
    """Benettin's accumulators of the tangent vectors of a tangent-system state ``Y`` (of the
    problem ``tangent`` from :func:`tangent_problem`): ``l_k + log R_kk`` for the QR
    decomposition of the directions in the inner product of :func:`tangent_weights`, the log
    growth of each vector as if re-orthonormalised now (``m`` values)."""
    n, na, m = (int(v) for v in tangent.ip[-N_META : -N_META + 3])
    w = tangent.p[-(n + na) - 2 : -2]
    _, U, log_size, _ = tangent_state(Y, n, na, m)
    _, R = np.linalg.qr(np.sqrt(w)[:, None] * U)
    return log_size + np.log(np.abs(np.diag(R)))


def tangent_columns(Y: np.ndarray, n: int, na: int, m: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Split a tangent-system state into the model state ``y``, the tangent vectors ``V``
    (``(n + na, m)``) and the accumulated log volume change at events (see
    :func:`tangent_state` for the directions and log sizes, which never overflow)."""
    y, U, log_size, log_det = tangent_state(Y, n, na, m)
    return y, U * np.exp(log_size)[None, :], log_det
