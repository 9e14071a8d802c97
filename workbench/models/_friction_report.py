"""What every run with LuGre friction records about its friction law, and what it says of it.

The normalised LuGre law (:mod:`workbench.models.friction`) lets the friction coefficient
|F_t| / F_n leave the range of any surface when its bristle damping is not passive: with the
paper's constant s1 = 316 s m-1 it reached 25-50 against mu_s = 0.15 in the nine-bar's Sec. 4.2
case (issue 29). So a LuGre run of a mechanism always records, per clearance joint (dims
``time``, ``joint``):

- ``friction_ratio`` (1): the law's |F_t| / F_n at the records (0 out of contact), with
  the bristle deflection on its invariant set |z| <= max(mu_s, mu_k) / s0
  (:func:`workbench.models._reduced.lugre_diagnostic`);
- ``time_above_static_friction`` (s): the time since the record start spent in contact with
  |F_t| / F_n > mu_s;
- ``time_beyond_friction_law`` (s): the same beyond the law's envelope 2 mu_s + s2 |v_t|
  (:func:`workbench.models.friction.lugre_envelope`).

and the bristle deflection ``lugre_z`` (m). The two times are quadratures integrated with the
motion (states with a 0/1 rate from the right-hand side), so they do not depend on the record
spacing: a bristle transient of a few microseconds between two records is counted. Each is
exact to within the solver's step at each crossing of its level (the integrand jumps there);
their characteristic size (:data:`TIME_SCALE`) keeps them out of the step-size control. The
largest coefficient is taken at the records, whose spacing bounds what it can see.

The coefficient is the law's on the invariant set of its bristles because an explicit method
at its stability bound (DOP853 on LuGre, benchmarks/lugre_stiffness.py) integrates the stiff
bristle state accurately at its steps but not in between: its stages, and its dense output at
the records, can put z outside the set (measured: at a small fraction of the records of a
default Sec. 4.2 run with DOP853 at rtol 1e-6, at none with ARK548, which integrates the
bristles implicitly). Those values are the integrator's error, and ``friction_force`` (and
what depends on it at the records: torques, accelerations) carries it there; the law's
coefficient does not. :func:`friction_summary` puts the diagnostics in the run's summary line and
:func:`friction_warnings` says where a run leaves the envelope and why, and where the records'
bristle deflection left its invariant set.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from workbench.models._base import Quantity
from workbench.models.friction import lugre_passive_damping, lugre_passive_damping_velocity

__all__ = [
    "DIAGNOSTICS",
    "TIME_SCALE",
    "diagnostic_outputs",
    "diagnostic_states",
    "friction_summary",
    "friction_warnings",
]

#: the variables every LuGre run of a mechanism records
DIAGNOSTICS = (
    "friction_ratio",
    "time_above_static_friction",
    "time_beyond_friction_law",
    "lugre_z",
)
#: characteristic size of the time quadratures for the solver's atol (s): their error (up to a
#: step at each crossing of a level) never limits the step
TIME_SCALE = 1e6


def diagnostic_outputs() -> list[Quantity]:
    """The two time quadratures as output variables (dim ``joint``)."""
    jd = ("joint",)
    return [
        Quantity(
            "time_above_static_friction",
            "s",
            "time in contact with |F_t| / F_n above mu_s since record start",
            jd,
        ),
        Quantity(
            "time_beyond_friction_law",
            "s",
            "time in contact with |F_t| / F_n above 2 mu_s + sigma2 |v_t| since record start",
            jd,
        ),
    ]


def diagnostic_states(joints: Sequence[str]) -> list[Quantity]:
    """The internal quadratures behind :func:`diagnostic_outputs`: per joint its time above
    mu_s, then its time beyond the envelope (s)."""
    out = []
    for j in joints:
        out += [
            Quantity(f"_above_{j}", "s", f"time above mu_s at joint {j} since t0"),
            Quantity(f"_beyond_{j}", "s", f"time beyond the friction law's envelope at {j}"),
        ]
    return out


def _totals(ds, name: str) -> dict[str, float]:
    """Per joint, the last finite value of a cumulative time (s)."""
    values = np.asarray(ds[name].values, float)
    out = {}
    for k, joint in enumerate(ds["joint"].values):
        finite = values[np.isfinite(values[:, k]), k]
        out[str(joint)] = float(finite[-1]) if finite.size else float("nan")
    return out


def _largest(ds) -> tuple[float, str, float]:
    """The largest |F_t| / F_n at the records, its joint and time (s)."""
    mu = np.asarray(ds["friction_ratio"].values, float)
    if not np.isfinite(mu).any():
        return float("nan"), "", float("nan")
    i, k = np.unravel_index(int(np.nanargmax(mu)), mu.shape)
    return float(mu[i, k]), str(ds["joint"].values[k]), float(ds["time"].values[i])


def _has(ds) -> bool:
    return all(name in ds for name in DIAGNOSTICS)


def friction_summary(ds, params: Mapping[str, float]) -> str:
    """The run's LuGre diagnostics in words ('' for a run without them)."""
    if not _has(ds):
        return ""
    top, joint, when = _largest(ds)
    above = _totals(ds, "time_above_static_friction")
    beyond = _totals(ds, "time_beyond_friction_law")

    def times(t: dict[str, float]) -> str:
        return ", ".join(f"{j} {v:.3g} s" for j, v in t.items())

    return (
        f"; LuGre |F_t|/F_n up to {top:.3g} at the records ({joint}, t = {when:.6g} s), "
        f"time above mu_s = {params['lugre_mu_s']:g}: {times(above)}; beyond 2 mu_s + "
        f"sigma2 |v_t|: {times(beyond)}"
    )


def friction_warnings(ds, params: Mapping[str, float]) -> list[str]:
    """One sentence per joint whose LuGre friction coefficient left the law's envelope
    (time beyond it > 0), with the likely cause: a bristle damping that is not passive; and
    one per joint whose recorded bristle deflection left its invariant set (an integration
    error at those records)."""
    if not _has(ds):
        return []
    beyond = _totals(ds, "time_beyond_friction_law")
    mu = np.asarray(ds["friction_ratio"].values, float)
    out = _outside_warnings(ds, params)
    for k, (joint, spent) in enumerate(beyond.items()):
        if not spent > 0.0:
            continue
        column = mu[:, k]
        top = float(np.nanmax(column)) if np.isfinite(column).any() else float("nan")
        out.append(
            f"LuGre friction at joint {joint} left its law's range: |F_t| / F_n above 2 mu_s + "
            f"sigma2 |v_t| for {spent:.3g} s (largest at the records {top:.3g}, mu_s = "
            f"{params['lugre_mu_s']:g}). {_damping_cause(params)}"
        )
    return out


def _outside_warnings(ds, params: Mapping[str, float]) -> list[str]:
    """Records whose bristle deflection lies outside |z| <= max(mu_s, mu_k) / sigma0."""
    bound = max(params["lugre_mu_s"], params["lugre_mu_k"]) / params["lugre_sigma0"]
    z = np.abs(np.asarray(ds["lugre_z"].values, float))
    out = []
    for k, joint in enumerate(ds["joint"].values):
        outside = z[:, k] > bound * (1.0 + 1e-9)
        if outside.any():
            out.append(
                f"LuGre bristle deflection at joint {joint} outside its invariant set |z| <= "
                f"{bound:.3g} m at {int(outside.sum())} of {outside.size} records (up to "
                f"{float(np.nanmax(z[:, k])):.3g} m): an integration error between steps (the "
                "dense output of the stiff bristle state by an explicit method), so "
                "friction_force and what depends on it are off there (friction_ratio "
                "takes the law's value); solver.method = 'ark548' integrates the bristles "
                "implicitly."
            )
    return out


def _damping_cause(params: Mapping[str, float]) -> str:
    """Whether the scene's bristle damping is passive, with the bound it breaks."""
    s1, v_d = params["lugre_sigma1"], params["lugre_damping_velocity"]
    mu_k, mu_s, s2 = params["lugre_mu_k"], params["lugre_mu_s"], params["lugre_sigma2"]
    if v_d <= 0.0:
        bound = lugre_passive_damping(mu_k, mu_s, s2)
        if s1 > bound:
            return (
                f"The constant bristle damping lugre_sigma1 = {s1:g} s m-1 is not passive (a "
                f"constant damping is passive up to sigma2 mu_k / (mu_s - mu_k) = {bound:.3g} "
                "s m-1, Barabanov & Ortega 2000); let it fade with the sliding speed "
                "(lugre_damping_velocity > 0, Olsson et al. 1998) or lower it."
            )
    elif v_d > lugre_passive_damping_velocity(mu_k, s1):
        return (
            f"lugre_damping_velocity = {v_d:g} m s-1 exceeds the passive limit 4 sqrt(2 e) "
            f"mu_k / sigma1 = {lugre_passive_damping_velocity(mu_k, s1):.3g} m s-1 for "
            f"lugre_sigma1 = {s1:g} s m-1."
        )
    return "The bristle damping is passive: the overshoot comes from the bristle dynamics."
