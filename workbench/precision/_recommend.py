"""The cheapest setting of a work-precision study under a target error (:func:`recommend`)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
import xarray as xr

from workbench.precision._measures import LIMIT_BITS

__all__ = ["Recommendation", "recommend"]


@dataclass(frozen=True)
class Recommendation:
    """The setting :func:`recommend` picks: a value, not a study (the evidence is the study).

    Attributes
    ----------
    method : str
        Solver method.
    rtol : float
        rtol = atol of the setting.
    wall_time : float
        Solver wall time of the study's long run at this setting, s.
    errors : Mapping[str, float]
        The errors that decided (dimensionless; see :func:`accuracy`).
    target : float
        The target every one of them is below.

    The repr is one line that reads as the choice, e.g.
    ``Recommendation(method='dop853', rtol=1e-08, wall_time=0.0123 s, short_error=2.1e-09,
    peak_error=3.4e-10, target=1e-06)``.
    """

    method: str
    rtol: float
    wall_time: float
    errors: Mapping[str, float] = field(hash=False)
    target: float

    def __repr__(self) -> str:
        errors = ", ".join(f"{k}={v:.2g}" for k, v in self.errors.items())
        return (
            f"Recommendation(method={self.method!r}, rtol={self.rtol:g}, "
            f"wall_time={self.wall_time:.3g} s, {errors}, target={self.target:g})"
        )


def _limited(wp: xr.Dataset, errors: Sequence[str]) -> xr.DataArray:
    """Settings whose errors among ``errors`` are flagged at the reference's limit (a study
    without the flag, from before it existed, has none flagged)."""
    if "at_reference_limit" not in wp:
        return xr.zeros_like(wp.status, dtype=bool)
    mask = sum(LIMIT_BITS.get(e, 0) for e in errors)
    return (wp.at_reference_limit & mask) != 0


def _where(selected: xr.DataArray) -> list[tuple[str, float]]:
    idx = np.argwhere(selected.transpose("solver_method", "rtol").values)
    return [(str(selected.solver_method.values[i]), float(selected.rtol.values[j])) for i, j in idx]


def recommend(
    wp: xr.Dataset, target: float, *, errors: Sequence[str] = ("short_error", "peak_error")
) -> Recommendation:
    """The cheapest (method, tolerance) of a work-precision study whose errors are all below
    ``target``.

    By default the deterministic errors (a) and (b) decide; the long-run statistic and the event
    count of a chaotic run have a sampling-noise floor (about ``statistic_noise_floor`` in the
    study's attributes) that no tolerance removes. A setting whose deciding errors are flagged
    in ``at_reference_limit`` (within 3x of the reference's own error) is never recommended:
    its error measures the reference.

    Parameters
    ----------
    wp : xarray.Dataset
        From :func:`accuracy`.
    target : float
        Largest acceptable error (dimensionless).
    errors : sequence of str
        The error variables that must all be below ``target``.

    Returns
    -------
    Recommendation
        A frozen dataclass rather than a Dataset: it is one choice read off the study, whose
        evidence (every error and cost) is ``wp`` itself.

    Raises
    ------
    ValueError
        If no setting meets the target, naming the best error reached; or if only settings at
        the reference's limit do, naming them.

    Examples
    --------
    >>> from workbench.precision import accuracy
    >>> wp = accuracy({"model": {"name": "duffing"}, "run": {"cycles": 5}},
    ...               methods=["dop853"], tolerances=[1e-4, 1e-8])
    >>> r = recommend(wp, 1e-6)
    >>> r.method, r.rtol
    ('dop853', 1e-08)
    """
    worst = wp[list(errors)].to_array("error").max("error")
    meets = (worst < target) & (wp.status == 0)
    limited = _limited(wp, errors)
    ok = meets & ~limited
    if not bool(ok.any()):
        if bool(meets.any()):
            ref_error = wp.attrs.get("reference_error", math.nan)
            ref_tol = wp.attrs.get("reference_tolerance", math.nan)
            shown = ", ".join(
                f"{m} {r:g} ({float(worst.sel(solver_method=m, rtol=r)):.2g})"
                for m, r in _where(meets & limited)
            )
            raise ValueError(
                f"the settings that reach errors below target={target!r} ({shown}) are at the "
                f"reference's limit (reference_error {ref_error:.2g} at rtol {ref_tol:g}): "
                "their errors "
                "measure the reference, not the setting. Run the study with a tighter reference "
                "(at least 100x below the tolerances that matter)"
            )
        best = float(worst.min())
        raise ValueError(
            f"no setting reaches errors below target={target!r}; the best is "
            f"{best:.3g}: loosen the target or add tighter tolerances"
        )
    cost = wp.wall_time.where(ok)
    idx = np.unravel_index(int(np.nanargmin(cost.values)), cost.shape)
    pick = wp.isel(solver_method=idx[0], rtol=idx[1])
    return Recommendation(
        method=str(pick.solver_method.values),
        rtol=float(pick.rtol),
        wall_time=float(pick.wall_time),
        errors=MappingProxyType({e: float(pick[e]) for e in errors}),
        target=float(target),
    )
