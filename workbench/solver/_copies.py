"""Several copies of a problem integrated side by side with one step-size sequence, as a problem
the compiled loop integrates (see :mod:`workbench.solver._templates.copies_hooks`)."""

from __future__ import annotations

import numpy as np

from workbench.solver._compile import copies_for
from workbench.solver._problem import Problem
from workbench.solver._tangent import state_scale
from workbench.solver._templates.copies_hooks import SLOTS

__all__ = ["copies_problem", "shrink_counts", "split_copies"]


def copies_problem(
    problem: Problem,
    Y: np.ndarray,
    AUX: np.ndarray,
    *,
    separations: np.ndarray | None = None,
    growth: np.ndarray | None = None,
    measured: int | None = None,
) -> Problem:
    """The problem's model integrated for every row of ``Y`` (states) and ``AUX`` (discrete
    states) at once, from ``problem.t0``.

    With ``separations`` (scaled, one per copy after the first) and ``growth`` (log change,
    one per copy after the first), copies 1.. are renormalised towards copy 0 where their
    separation has grown by ``exp(growth)`` or shrunk by the same factor; their accumulated
    log growth and renormalisation counts follow the copies' discrete states in ``aux`` (see
    :func:`split_copies` and :func:`shrink_counts`). ``measured`` (default all) is how many
    leading states the separations are measured in.
    """
    Y = np.atleast_2d(np.asarray(Y, dtype=float))
    AUX = np.atleast_2d(np.asarray(AUX, dtype=float))
    k, n = Y.shape
    na = problem.aux0.size
    if n != problem.y0.size or AUX.shape != (k, na):
        raise ValueError(
            f"copies need states of shape (k, {problem.y0.size}) and discrete states of shape "
            f"(k, {na}); got {Y.shape!r} and {AUX.shape!r}"
        )
    renorm = separations is not None
    ne = problem.event_direction.size
    p = [problem.p, state_scale(problem)]
    aux0 = [AUX.ravel(), np.zeros(SLOTS * (k - 1))]
    direction = [np.tile(problem.event_direction, k)]
    surface = [np.tile(problem.event_surface, k)]
    if renorm:
        sep = np.broadcast_to(np.asarray(separations, dtype=float), (k - 1,))
        gro = np.broadcast_to(np.asarray(growth, dtype=float), (k - 1,))
        if np.any(~(sep > 0)) or np.any(~(gro > 0)):
            raise ValueError(
                f"separations {sep!r} and growth {gro!r} must be positive, one per copy after "
                "the first"
            )
        p.append(np.column_stack([sep, gro]).ravel())
        direction.append(np.ones(2 * (k - 1), dtype=np.int64))  # growth, shrinkage
        surface.append(np.zeros(2 * (k - 1), dtype=bool))  # renormalisations: time events
    nm = n if measured is None else int(measured)
    meta = np.array([n, na, ne, k, problem.p.size, int(renorm), nm], dtype=np.int64)
    return Problem(
        hooks=copies_for(problem.hooks).__name__,
        states=tuple(problem.states) * k,
        y0=Y.ravel(),
        p=np.concatenate(p),
        ip=np.concatenate([problem.ip, meta]),
        aux0=np.concatenate(aux0),
        event_direction=np.concatenate(direction),
        event_surface=np.concatenate(surface),
        atol_scale=np.tile(problem.atol_scale, k),
        t0=problem.t0,
        work_size=problem.work_size,
        failure=problem.failure,
    )


def split_copies(
    y: np.ndarray, aux: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """From a copies-system state and discrete state: the copies' states (k, n), discrete
    states (k, na), and for copies 1.. their accumulated log growth at renormalisations and
    the number of renormalisations (on growth and on shrinkage)."""
    na = (aux.size - SLOTS * (k - 1)) // k
    A = aux[: k * na].reshape(k, na).copy()
    extra = _renormalisation_states(aux, k)
    return y.reshape(k, -1).copy(), A, extra[:, 0].copy(), extra[:, 1].copy()


def shrink_counts(aux: np.ndarray, k: int) -> np.ndarray:
    """From a copies-system discrete state: for copies 1.. the number of their
    renormalisations that were on shrinkage (included in :func:`split_copies`' counts)."""
    return _renormalisation_states(aux, k)[:, 3].copy()


def _renormalisation_states(aux: np.ndarray, k: int) -> np.ndarray:
    """The discrete states (L, N, P, S) of copies 1.. (see
    :mod:`workbench.solver._templates.copies_hooks`), shape (k - 1, SLOTS)."""
    return aux[aux.size - SLOTS * (k - 1) :].reshape(k - 1, SLOTS)
