"""Ensembles of a scene: the same run from initial states perturbed at round-off-like size.

A clearance mechanism is chaotic (its largest Lyapunov exponent is tens of 1/s; docs/analysis.md
gives the nine-bar's chaos case): a peak of one run is one sample of a distribution, and a
difference of 1e-12 in the initial state changes it within a few crank cycles. An ensemble runs
a scene several times, realisation k starting from

    y0_k = y0 + perturbation * atol_scale * N_k(0, 1)

where ``atol_scale`` is the model's characteristic size of each state (for the clearance
mechanisms: the clearance c for positions, c omega for rates; see
:attr:`workbench.models.Problem.atol_scale`) and ``N_k`` is a vector of standard normal draws
from a generator seeded by ``k``. Realisation 0 is the unperturbed scene.

A scene asks for a realisation with the ``[run]`` keys ``realisation`` (integer >= 0, default
0) and ``perturbation`` (relative size, default 1e-9); an ensemble is a campaign over
``[sweep] realisation = {start = 0, stop = 15, num = 16}`` (or a list of integers).

>>> import numpy as np
>>> from workbench.solver import Problem
>>> pb = Problem(hooks="", states=(), y0=np.zeros(3), p=np.zeros(0), atol_scale=np.full(3, 1e-4))
>>> a, b = perturb_initial_state(pb, 1), perturb_initial_state(pb, 1)
>>> bool((a.y0 == b.y0).all()), bool((perturb_initial_state(pb, 0).y0 == 0).all())
(True, True)
>>> float(np.abs(a.y0).max()) < 1e-12
True
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from workbench._attributes import variable
from workbench.solver import Problem

__all__ = [
    "DEFAULT_PERTURBATION",
    "REALISATION_ATTRS",
    "perturb_initial_state",
    "scene_perturbation",
]

DEFAULT_PERTURBATION = 1e-9
REALISATION_ATTRS = variable(
    "realisation of the ensemble (0: unperturbed initial state; k > 0: initial "
    "state perturbed by perturbation * atol_scale * N(0, 1), generator seeded by k)",
    standard_name="realization",
)


def perturb_initial_state(
    problem: Problem, realisation: int = 0, size: float = DEFAULT_PERTURBATION
) -> Problem:
    """The problem of realisation ``realisation`` of an ensemble.

    Parameters
    ----------
    problem : Problem
        As built by the model from the scene.
    realisation : int
        0 returns ``problem`` itself (the unperturbed run); k > 0 adds
        ``size * problem.atol_scale * z`` to ``problem.y0``, with ``z`` the first ``len(y0)``
        standard normal draws of ``numpy.random.default_rng(k)``. The draws follow the order of
        the state, so states a model appends at the end (e.g. energy quadratures) do not change
        the perturbation of the others.
    size : float
        Relative size of the perturbation (1), in units of each state's characteristic size.

    Returns
    -------
    Problem
        A copy with the perturbed ``y0`` (bit-identical for the same ``realisation`` and
        ``size``); everything else shared with ``problem``.
    """
    if realisation == 0 or problem.y0.size == 0:
        return problem
    z = np.random.default_rng(realisation).standard_normal(problem.y0.size)
    return dataclasses.replace(problem, y0=problem.y0 + size * problem.atol_scale * z)


def scene_perturbation(run: Mapping) -> tuple[int, float]:
    """``(realisation, perturbation)`` of a scene's validated ``[run]`` table (defaults 0 and
    :data:`DEFAULT_PERTURBATION`)."""
    return int(run.get("realisation", 0)), float(run.get("perturbation", DEFAULT_PERTURBATION))
