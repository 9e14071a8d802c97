"""The fiducial trajectory of a scene's window and nearby copies of it, integrated side by side
in one step-size sequence and renormalised towards it whenever their separation has grown or
shrunk by a set factor (Benettin, Galgani & Strelcyn 1976, Phys. Rev. A 14, 2338; Benettin,
Galgani, Giorgilli & Strelcyn 1980, Meccanica 15, 9): the runs that
:func:`workbench.analysis.lle_from_equations` reads its estimates from.

The copies share the fiducial trajectory's steps, so that their integration errors are nearly
equal and their separation is integrated far more accurately than the tolerance (two
separately integrated trajectories differ by the tolerance times the ~1e4-fold amplification of
an impact's timing error, a noise floor far above any useful separation).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from workbench.analysis._window import Window
from workbench.solver import (
    copies_problem,
    shrink_counts,
    split_copies,
    state_scale,
    tangent_growths,
    tangent_problem,
)

__all__ = ["follow_copies", "joined"]

#: records per measured window (running estimate, batch means)
RECORDS = 400


def follow_copies(
    prep: Window,
    separations: np.ndarray,
    growth: np.ndarray,
    length: float,
    rtol: float,
    seed: int,
    *,
    variational: bool = False,
    resume: dict | None = None,
) -> dict:
    """Integrate the fiducial trajectory and one copy per entry of ``separations`` (scaled,
    dimensionless) side by side over ``length`` seconds, each renormalised whenever its log
    growth reaches ``+growth`` or ``-growth`` (its entry of ``growth``; see
    :mod:`workbench.solver._templates.copies_hooks`); with ``variational`` the fiducial also
    carries a tangent vector (the variational equations with saltation,
    :mod:`workbench.solver._tangent`), so that both estimates follow one trajectory. Returns
    the record ``times`` (s), every copy's accumulated log growth at them (renormalisations
    plus the current separation), the tangent vector's (``variational``), renormalisation
    counts since the start (``renormalisations``, of which ``shrinkages`` on shrinkage),
    solver statistics, and the system and its end state to continue from (``resume``: a run
    returned by this function, continued from its end over ``length`` seconds with its
    copies, tolerance and tangent vector)."""
    pb = prep.problem
    n, na = pb.y0.size, pb.aux0.size
    scale = state_scale(pb)
    separations = np.asarray(separations, dtype=float)
    k = separations.size + 1
    if resume is None:
        rng = np.random.default_rng(seed)
        u = rng.standard_normal(n)
        u /= np.linalg.norm(u)
        base = pb
        if variational:
            base = tangent_problem(
                pb, np.concatenate([u * scale, np.zeros(na)])[:, None], normalisation="continuous"
            )
        Y = np.tile(base.y0, (k, 1))
        Y[1:, n:] = 0.0  # only the fiducial copy carries the tangent vector
        Y[1:, :n] += separations[:, None] * u[None, :] * scale[None, :]
        system = copies_problem(
            base, Y, np.tile(base.aux0, (k, 1)), separations=separations, growth=growth,
            measured=n,
        )  # fmt: skip
        first, t0 = system, pb.t0
    else:
        system, base, rtol = resume["system"], resume["base"], resume["rtol"]
        Y_end, aux_end, t0 = resume["end"]
        first = dataclasses.replace(system, y0=Y_end.copy(), aux0=aux_end.copy(), t0=t0)
        variational = resume["variational"] is not None
    t_rec = t0 + np.linspace(0.0, length, RECORDS + 1)
    total = np.zeros((t_rec.size, k - 1))
    tangent = np.zeros(t_rec.size)
    if resume is not None:
        total[0] = resume["total"][-1]
        tangent[0] = resume["variational"][-1] if variational else 0.0
    res = prep.solve(first, t_rec[1:], rtol)
    keys = ("steps", "rejected_steps", "rhs_evaluations", "events")
    stats = {key: res.stats[key] for key in keys}
    counts = np.zeros(k - 1)
    for r in range(1, t_rec.size):
        Yr, _, logs, counts = split_copies(res.Y[r - 1], res.AUX[r - 1], k)
        d = np.linalg.norm((Yr[1:, :n] - Yr[0, :n]) / scale, axis=1)
        if not np.all(d > 0) or not np.all(np.isfinite(d)):
            raise FloatingPointError(
                f"a copy coincides with the fiducial trajectory or left it at t = "
                f"{t_rec[r]:g} s (scaled distances {d!r}); choose other separations"
            )
        total[r] = logs + np.log(d / separations)
        if variational:  # the tangent vector's log growth
            tangent[r] = tangent_growths(base, Yr[0])[0]
    return {
        "times": t_rec,
        "total": total,
        "variational": tangent if variational else None,
        "renormalisations": counts,
        "shrinkages": shrink_counts(res.AUX[-1], k),
        "stats": stats,
        "rtol": rtol,
        "system": system,
        "base": base,
        "end": (res.Y[-1].copy(), res.AUX[-1].copy(), float(t_rec[-1])),
    }


def joined(a: dict, b: dict) -> dict:
    """Run ``a`` followed by its continuation ``b`` (:func:`follow_copies` with ``resume=a``):
    records of both (``b``'s first is ``a``'s last), statistics summed."""
    out = dict(b)
    out["times"] = np.concatenate([a["times"], b["times"][1:]])
    out["total"] = np.concatenate([a["total"], b["total"][1:]])
    if a["variational"] is not None:
        out["variational"] = np.concatenate([a["variational"], b["variational"][1:]])
    out["stats"] = {k: a["stats"][k] + b["stats"][k] for k in a["stats"]}
    return out
