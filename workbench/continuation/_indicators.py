"""Chaos indicators of one run, computed in a campaign's worker, and the campaign that maps them
over parameters.

Per point: the **period of the strobe** (the least k with x(t + kT) = x(t) over the recorded
strobe samples, 0 when none up to :data:`MAX_PERIOD`: quasi-periodic or chaotic), the **0-1
test's K** (Gottwald & Melbourne 2004, 2009) on the strobe samples of every recorded variable,
and the **largest Lyapunov exponent** with its error (:func:`workbench.continuation.
point_exponent`): where the strobe has a period k, ``ln |mu_max| / (k T)`` of the period-k
orbit Newton finds from the state where the run ended (a trajectory method cannot measure a
strongly contracting orbit: :mod:`workbench.continuation._exponent`), else over
:func:`lle_cycles` forcing periods (grown to a 10 % error or the sign decided beyond three
errors) from where the run ended, from the variational equations with saltation for a model
with an analytic Jacobian, or by the linearised two-trajectory method (the mechanisms),
checked by the variational exponent on the same trajectory: the map's own precision (the fast
protocol of :func:`~workbench.continuation.point_exponent`), nothing integrated twice. On a
reproducible random subset of a map's points the full protocol runs too (:func:`chaos_map`,
:func:`full_subset`), and the map says how the two agree (:func:`subset_agreement`). A failure of
the exponent's runs is recorded (``lle_status``), not raised, so one hard point does not stop a
map; whether the exponent converged is recorded beside it (``lle_converged``, and
``lle_unmet``: which of its conditions did not hold,
:data:`workbench.continuation._exponent.UNMET`).
"""

from __future__ import annotations

import functools
import hashlib
import math

import numpy as np
import xarray as xr

from workbench._attributes import flags, variable
from workbench.analysis import poincare_section, zero_one_test
from workbench.archive import save_run
from workbench.campaign import expand_sweep, run_campaign
from workbench.continuation._exponent import (
    FAST_NOT_RUN,
    MAP_SIGN,
    MAP_TARGET,
    METHODS,
    UNMET,
    point_exponent,
)
from workbench.scene import Scene, SceneSource, load_scene

__all__ = [
    "MAX_PERIOD",
    "chaos_indicators",
    "chaos_map",
    "lle_cycles",
    "strobe_period",
    "strobe_zero_one",
]

#: the longest strobe period looked for (forcing periods)
MAX_PERIOD = 16
#: two strobe samples are the same point when they differ by less than this fraction of the
#: largest magnitude of their variable
PERIOD_TOLERANCE = 1e-4
LLE_STATUS = flags(
    "outcome of the exponent's runs",
    ["ok", "failed", "upper_bound"],
    comment="upper_bound: lle is an upper bound (the Floquet multipliers are below the noise "
    "of the copies' differences; lle_stderr NaN)",
)
LLE_METHOD = flags(
    "how the largest Lyapunov exponent was measured",
    list(METHODS),
    **{f"method_{k}": v for k, v in METHODS.items()},
)
LLE_CONVERGED = flags(
    "the largest Lyapunov exponent converged, and on which rule",
    ["not_converged", "converged", "converged_on_sign"],
    comment="nonzero where every convergence condition the map runs holds (lle_unmet = 0). "
    "Trajectory methods: the window (one start from where the point's run ended, its error "
    "from batch means) grew, doubling, until its standard error was at most the map's target "
    "(lle_target) of the estimate (1: converged) or the sign was decided beyond lle_sign "
    "standard errors (2: converged_on_sign, the error target not met), whichever first; with "
    "the variational exponent on the same trajectory (copies) or the sum check (variational). "
    "floquet: the exponent moves by at most 20 % with its check (1). 0 for an upper bound, a "
    "failed run, or a window whose budget ended before either rule held. Not run in a map's "
    "fast protocol (their cost; lle_full_protocol marks the points where the full protocol "
    "ran too): " + "; ".join(f"{m}: {', '.join(c)}" for m, c in FAST_NOT_RUN.items()),
)
LLE_UNMET = variable(
    "the convergence conditions of the largest Lyapunov exponent that failed",
    "1",
    flag_masks=np.array([1 << i for i in range(len(UNMET))], np.int16),
    flag_meanings=" ".join(u.replace(" ", "_") for u in UNMET),
    comment="bit field, 0: converged. error_target: after the window's budget the "
    "standard error is above the target of the estimate (lle_target) and the sign is not "
    "decided beyond lle_sign standard errors (the full protocol: above 3 %, no sign rule); "
    "variants: the two-trajectory separation and growth variants disagree; tolerance_check: "
    "the run at rtol / 100 disagrees; sum_check: the spectrum's sum and the integrated volume "
    "rate differ; floquet_check: the Floquet exponent moves by more than 20 % with its check; "
    "upper_bound: see lle_status; failed: the exponent's runs failed; variational: the "
    "copies' exponent and the variational one on the same trajectories differ; other: a "
    "condition of the estimator not named here",
)


LLE_SEEDED = flags(
    "Newton's periodic orbit started from the previous point's along the map's axis",
    ["from_run_end", "from_neighbour"],
    comment="a map that carries state along an axis (chaos_map with along): where the "
    "previous point was periodic, Newton starts from its orbit at the strobe and keeps the "
    "orbit it finds there when that is the orbit the point's run ended on (1); else it starts "
    "from the state the run ended in (0)",
)
LLE_FULL_PROTOCOL = flags(
    "the full protocol of the exponent ran at this point too",
    ["fast_only", "full_protocol"],
    comment="1 on the map's random subset (lle_full_fraction of the points, at least 3, "
    "chosen from the points' parameter values and lle_full_seed): the exponent measured again "
    "by the full protocol (trajectory methods: four independent starts after the transient, "
    "the separation and growth variants, a 3 % error target; floquet: Newton from where the "
    "point's run ended, to the orbit's tolerance, at the scene's rtol, checked with a 100x "
    "larger copies' step) in lle_full and lle_full_stderr; the map's attributes lle_full_* say "
    "how it agrees with lle. Floquet's starts where the run ended because a periodic orbit's "
    "multipliers can depend on its history (the Lankarani-Nikravesh law holds each contact's "
    "onset velocity: a lasting-contact orbit is one of a family), so that integrated again it "
    "can land on another member of the family, with another exponent",
)


def strobe_period(samples: np.ndarray, tolerance: float = PERIOD_TOLERANCE) -> int:
    """The least k (1 .. :data:`MAX_PERIOD`) such that every strobe sample of the second half
    of the series equals the one k periods later (rows: samples, columns: variables; equal
    within ``tolerance`` times each column's largest magnitude), or 0 when there is none
    (quasi-periodic or chaotic motion, or too few samples: at least 2 k + 1 are needed). The
    first half is left to what remains of a transient (a continued point settles for only a
    few cycles before its records)."""
    x = np.asarray(samples, dtype=float)
    x = x.reshape(x.shape[0], -1)
    x = x[np.isfinite(x).all(axis=1)]
    x = x[x.shape[0] // 2 :]
    size = np.max(np.abs(x), axis=0) if x.size else np.zeros(0)
    tol = tolerance * np.where(size > 0, size, 1.0)
    for k in range(1, MAX_PERIOD + 1):
        if x.shape[0] < 2 * k + 1:
            break
        if np.all(np.abs(x[k:] - x[:-k]) <= tol):
            return k
    return 0


def lle_cycles(scene: Scene) -> int:
    """Forcing periods over which a map point's exponent is measured: a fifth of the recorded
    cycles, at least 10 (the exponent's batch-means error needs ten batches)."""
    return max(10, scene.run["cycles"] // 5)


def chaos_indicators(
    scene: Scene,
    run: xr.Dataset,
    *,
    full_protocol: bool = False,
    target: float = MAP_TARGET,
    sign: float = MAP_SIGN,
    seed=None,
    carry: bool = False,
) -> xr.Dataset:
    """The chaos indicators of one point (a campaign's ``per_point``): ``strobe_period``,
    ``zero_one_K`` (median over the recorded variables' components) and ``zero_one_K_<var>``
    (per variable, over its model dims), ``lle`` and ``lle_stderr`` (s-1), ``lle_per_period``
    (1), ``lle_method`` (floquet, variational or copies: :func:`workbench.continuation.
    point_exponent`), ``lle_status``, ``lle_converged`` and ``lle_unmet`` (why not; the
    estimator's own words in the attribute ``lle_detail``), and ``lle_full_protocol`` with
    ``lle_full`` and ``lle_full_stderr`` (s-1; NaN where the full protocol did not run).

    The exponent is measured by the fast protocol (a map's own precision,
    :func:`~workbench.continuation.point_exponent` with ``protocol="fast"``): Newton and the
    trajectory method start where the run ended (its ``end_state`` at ``end_time``), nothing
    is integrated again, and the trajectory method's window grows until its standard error is
    at most ``target`` of the estimate or its sign is decided beyond ``sign`` standard
    errors. With ``full_protocol`` the full protocol runs too (the check of the fast values on
    a subset of a map's points, :func:`chaos_map`).

    Parameters
    ----------
    scene : Scene
        The point's single-run scene (forced, recorded per period).
    run : xarray.Dataset
        Its run (:func:`workbench.simulate`, with the end-state attributes).
    full_protocol : bool
        Also measure the exponent by the full protocol (``lle_full``, ``lle_full_stderr``).
    target : float
        The fast protocol's relative error target (default :data:`~workbench.continuation.
        _exponent.MAP_TARGET`, 10 %).
    sign : float
        The fast protocol's sign rule: standard errors beyond which the sign is decided
        (default :data:`~workbench.continuation._exponent.MAP_SIGN`, 3).
    seed : (y, aux), optional
        A neighbouring point's periodic orbit at the strobe, where Newton starts first
        (:func:`~workbench.continuation.point_exponent`; from the run's end when it fails).
    carry : bool
        A map that carries state along an axis (:func:`chaos_map` with ``along``): add
        ``lle_seeded`` (1 where Newton's orbit came from ``seed``) and leave this point's
        periodic orbit (or None) in the attribute ``carry``, the next point's ``seed``.
    """
    section = poincare_section(run)
    out: dict = {}
    columns, ks = [], []
    for name in scene.variables:
        da = section[name].transpose("strobe", ...)
        values = da.values.reshape(da.sizes["strobe"], -1)
        columns.append(values)
        per = []
        for j in range(values.shape[1]):
            per.append(strobe_zero_one(values[:, j]))
        ks += per
        extra = [d for d in da.dims if d != "strobe"]
        shape = tuple(da.sizes[d] for d in extra)
        out[f"zero_one_K_{name}"] = (
            tuple(extra),
            np.array(per).reshape(shape),
            variable(f"0-1 test K of the strobe samples of {name}", "1"),
        )
    period = strobe_period(np.concatenate(columns, axis=1))
    out["strobe_period"] = (
        (),
        np.int16(period),
        variable(
            "period of the strobe samples in forcing periods (0: none up to "
            f"{MAX_PERIOD}: quasi-periodic or chaotic)",
            "1",
        ),
    )
    out["zero_one_K"] = (
        (),
        float(np.nanmedian(ks)) if np.isfinite(ks).any() else np.nan,
        variable("0-1 test K, median over the recorded variables", "1"),
    )
    period_s = float(run.attrs["forcing_period"])
    t, y, aux = run_end(run)
    exp = point_exponent(
        scene,
        period=period,
        cycles=lle_cycles(scene),
        state=y,
        discrete_state=aux,
        start_time=t,
        protocol="fast",
        target=target,
        sign=sign,
        seed=seed,
    )
    out["lle"] = (
        (),
        exp.value,
        variable("largest Lyapunov exponent", "s-1"),
    )
    out["lle_stderr"] = (
        (),
        exp.error,
        variable(
            "error of the largest Lyapunov exponent (batch means; floquet: its "
            "change with the copies' step or the tolerance, see lle_method)",
            "s-1",
        ),
    )
    out["lle_per_period"] = (
        (),
        exp.value * period_s,
        variable("largest Lyapunov exponent per forcing period", "1"),
    )
    out["lle_method"] = ((), np.int8(list(METHODS).index(exp.method)), LLE_METHOD)
    status = 1 if exp.failed else 2 if exp.bound else 0
    out["lle_status"] = ((), np.int8(status), LLE_STATUS)
    out["lle_converged"] = ((), np.int8(exp.converged_code), LLE_CONVERGED)
    out["lle_unmet"] = ((), np.int16(exp.unmet_code), LLE_UNMET)
    full = None
    if full_protocol:  # the full protocol on the same orbit: Newton from where the run ended
        full = point_exponent(
            scene,
            period=period,
            cycles=lle_cycles(scene),
            state=y,
            discrete_state=aux,
            start_cycles=scene.run["transient_cycles"] + scene.run["cycles"],
        )
    out["lle_full_protocol"] = ((), np.int8(full_protocol), LLE_FULL_PROTOCOL)
    out["lle_full"] = (
        (),
        full.value if full is not None else np.nan,
        variable("largest Lyapunov exponent by the full protocol", "s-1"),
    )
    out["lle_full_stderr"] = (
        (),
        full.error if full is not None else np.nan,
        variable("error of lle_full", "s-1"),
    )
    attrs = {"lle_detail": exp.detail}
    if carry:
        out["lle_seeded"] = ((), np.int8(exp.seeded), LLE_SEEDED)
        attrs["carry"] = exp.orbit
    return xr.Dataset(out, attrs=attrs)


def run_end(run: xr.Dataset) -> tuple[float, np.ndarray, np.ndarray | None]:
    """``(end_time, end_state, end_discrete_state)`` of a run (:func:`workbench.simulate`'s
    attributes; the discrete state None for a model without one), checked to lie whole forcing
    periods after the run's start, where the strobe map's phase is."""
    a = run.attrs
    if "end_state" not in a or "end_time" not in a:
        raise ValueError(
            "the run has no end_state and end_time attributes (the state it ended in, which "
            "workbench.simulate writes): simulate the point again"
        )
    t = float(a["end_time"])
    y = np.atleast_1d(np.asarray(a["end_state"], dtype=float))
    aux = a.get("end_discrete_state")
    aux = None if aux is None else np.atleast_1d(np.asarray(aux, dtype=float))
    period = float(a["forcing_period"])
    since = (t - float(run.time[0])) / period  # the first record is at phase 0
    if abs(since - round(since)) > 1e-6:
        raise ValueError(
            f"the run ended at t = {t!r} s, {since:.6g} forcing periods after its first record: "
            "a map point's run must end a whole number of periods after it (run.cycles)"
        )
    return t, y, aux


def strobe_zero_one(x: np.ndarray) -> float:
    """The 0-1 test's K of one series of strobe samples (:func:`workbench.analysis.
    zero_one_test`); 0 for a constant one (a period-1 orbit, where K is undefined), NaN for
    fewer than 100 samples."""
    x = x[np.isfinite(x)]
    if x.size < 100:
        return np.nan
    if np.ptp(x) <= PERIOD_TOLERANCE * max(np.max(np.abs(x)), 1e-300):
        return 0.0
    return float(zero_one_test(x).K)


#: default fraction of a map's points whose exponent is measured by the full protocol too
FULL_FRACTION = 0.05
#: the least number of such points (all of them in a smaller map)
FULL_LEAST = 3
#: a fast exponent agrees with the full protocol's within this fraction of it ...
AGREE_RELATIVE = 0.1
#: ... or within this many combined standard errors
AGREE_SIGMAS = 2.0


def subset_key(values: dict[str, float], seed: int) -> float:
    """A point's place in [0, 1) for the map's random subset: from a SHA-256 digest of its
    swept values (exactly, by their bits) and ``seed``, so that the same grid and seed pick the
    same points in any process, on resume and on another machine."""
    text = f"{int(seed)}|" + ";".join(f"{k}={float(v).hex()}" for k, v in sorted(values.items()))
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "big") / 2.0**64


def full_subset(grid, fraction: float, seed: int) -> tuple[np.ndarray, float]:
    """The flat indices of a grid's points (a :class:`workbench.campaign.SweepGrid`) whose
    exponent the full protocol measures too: the ``max(FULL_LEAST, ceil(fraction * size))``
    points (all for a smaller grid; none for ``fraction`` 0) of least :func:`subset_key`; and
    the largest key chosen (-1 for none), which decides a point from its own values."""
    keys = np.array([subset_key(grid.point(i), seed) for i in range(grid.size)])
    count = 0 if fraction == 0 else min(grid.size, max(FULL_LEAST, math.ceil(fraction * grid.size)))
    if count == 0:
        return np.zeros(0, np.int64), -1.0
    chosen = np.sort(np.argsort(keys, kind="stable")[:count])
    return chosen, float(keys[chosen].max())


_GRID = object()  # a grid map's point: no neighbour to carry from


def _map_point(
    scene: Scene,
    run: xr.Dataset,
    *,
    dims: tuple,
    subset_seed: int,
    threshold: float,
    orbit=_GRID,
    **rule,
) -> xr.Dataset:
    """:func:`chaos_indicators` of one map point, with the full protocol where the point's
    :func:`subset_key` is at most ``threshold`` (:func:`full_subset`); ``orbit``: the
    previous point's periodic orbit along a continued map's axis (None: none)."""
    values = {d: scene.parameters[d] if d in scene.parameters else scene.run[d] for d in dims}
    full = subset_key(values, subset_seed) <= threshold
    if orbit is _GRID:
        return chaos_indicators(scene, run, full_protocol=full, **rule)
    return chaos_indicators(scene, run, full_protocol=full, seed=orbit, carry=True, **rule)


def _carried_point(scene: Scene, run: xr.Dataset, *, seed=None, **kw) -> xr.Dataset:
    """:func:`_map_point` of a map that carries state along an axis (a continued sweep's
    ``per_point``: ``seed`` is the previous point's orbit)."""
    return _map_point(scene, run, orbit=seed, **kw)


def map_measurement(scene: Scene, fraction: float, seed: int, target: float, sign: float):
    """The per-point measurement of a chaos map (``run_campaign``'s ``per_point``): the
    indicators with the full protocol on the subset :func:`full_subset` picks. Its name (the
    campaign's identity) carries the settings, so a store measured with others is refused or
    recomputed, never mixed."""
    grid = expand_sweep(scene)
    _, threshold = full_subset(grid, fraction, seed)
    fn = functools.partial(
        _carried_point if scene.continuation else _map_point, dims=tuple(scene.sweep),
        subset_seed=int(seed), threshold=threshold, target=float(target), sign=float(sign),
    )  # fmt: skip
    fn.__module__ = __name__
    fn.__qualname__ = (
        f"chaos_indicators(full_fraction={fraction:g}, full_seed={int(seed)}, "
        f"target={target:g}, sign={sign:g})"
    )
    return fn


def subset_agreement(maps: xr.Dataset) -> dict:
    """How the full protocol's exponents (``lle_full``) agree with the fast ones (``lle``) on
    the points where both ran and are finite: attributes ``lle_full_points``,
    ``lle_full_agreeing`` (the fraction within AGREE_RELATIVE of the full value or
    AGREE_SIGMAS combined standard errors; a bound, whose error is NaN, by the first alone),
    ``lle_full_same_verdict`` (the fraction with the same verdict, chaotic where the exponent is
    positive, else regular) and ``lle_full_agreement`` (what they mean)."""
    chosen = maps["lle_full_protocol"].values == 1
    fast, full = maps["lle"].values, maps["lle_full"].values
    both = chosen & np.isfinite(fast) & np.isfinite(full)
    f, g = fast[both], full[both]
    combined = np.hypot(maps["lle_stderr"].values[both], maps["lle_full_stderr"].values[both])
    diff = np.abs(f - g)
    near = (diff <= AGREE_RELATIVE * np.abs(g)) | (diff <= AGREE_SIGMAS * combined)
    n = int(both.sum())
    return {
        "lle_full_points": n,
        "lle_full_agreeing": float(near.mean()) if n else np.nan,
        "lle_full_same_verdict": float(((f > 0) == (g > 0)).mean()) if n else np.nan,
        "lle_full_agreement": f"on the {n} points where the full protocol ran (lle_full_protocol "
        f"= 1) and both values are finite: lle_full_agreeing is the fraction whose fast lle lies "
        f"within {AGREE_RELATIVE:.0%} of lle_full or {AGREE_SIGMAS:g} combined standard errors, "
        "lle_full_same_verdict the fraction with the same verdict (chaotic: lle > 0, else "
        "regular)",
    }


def chaos_map(
    scene: SceneSource,
    store,
    *,
    client=None,
    workers: int | None = None,
    chunk: int | None = None,
    restart: bool = False,
    progress: bool = False,
    full_fraction: float = FULL_FRACTION,
    full_seed: int = 0,
    target: float = MAP_TARGET,
    sign: float = MAP_SIGN,
    along: str | None = None,
) -> xr.Dataset:
    """A campaign over the scene's ``[sweep]`` that measures the chaos indicators of every
    point in its worker (:func:`chaos_indicators`) and stores them over the parameter dims,
    beside the strobe samples the scene records (resumable like any campaign,
    :func:`workbench.run_campaign`).

    Each point's exponent is measured at the map's own precision (the fast protocol: from
    where its run ended, the error target ``target`` or the sign decided beyond ``sign``
    standard errors, whichever first); on a random subset of the points
    (``full_fraction`` of them, at least 3, chosen reproducibly from their parameter values
    and ``full_seed``: a resumed map picks the same) the full protocol runs too
    (``lle_full_protocol``, ``lle_full``, ``lle_full_stderr``), and the map's attributes say
    how the two agree (:func:`subset_agreement`), with ``lle_full_fraction``,
    ``lle_full_seed``, ``lle_target`` and ``lle_sign``.

    With ``along`` (a swept parameter; or a scene whose ``[sweep]`` has a ``continuation``)
    the map runs as a continued sweep upwards along that axis
    (:func:`workbench.continuation.continued_sweep`): each point's run starts from the state
    the previous point's ended in, with the per-point transient, and where the previous
    point was periodic, Newton starts from its orbit (``lle_seeded``; from the run's end
    where that fails).

    The scene should record per forcing period (``record.samples_per_period = 1``) at least
    100 cycles (the 0-1 test needs 100 samples). Draw the maps with
    :func:`workbench.plot.chaos_map_figure`.

    Parameters
    ----------
    scene : Scene, path or mapping
        A forced model with a ``[sweep]`` (with a ``continuation``: the map carries state
        along its axis, as with ``along``).
    store : str or PathLike
        Path of the campaign archive; blocks and manifest go to ``<store>.blocks/``.
    client : dask.distributed.Client, optional
        Run the blocks on this cluster (default: a local process pool).
    workers : int, optional
        Processes of the local pool (default: the CPUs available); not with ``client``.
    chunk : int, optional
        Points per block (task); default about four blocks per worker.
    restart : bool
        Discard whatever the store holds and start afresh.
    progress : bool
        Show a progress bar over points.
    full_fraction : float
        Fraction of the points (0 to 1) where the full protocol runs too (default 5 %; at
        least 3 points, all of a smaller map; 0: none).
    full_seed : int
        Seed of the subset's choice.
    target : float
        The fast protocol's relative error target (default 10 %).
    sign : float
        The fast protocol's sign rule, in standard errors (default 3).
    along : str, optional
        Carry state along this swept parameter (upwards, in the segments of
        :func:`~workbench.continuation.continued_sweep`); not with ``chunk``.

    Returns
    -------
    xarray.Dataset
        The campaign (:func:`workbench.run_campaign`) with the indicators of
        :func:`chaos_indicators` over the parameter dims.
    """
    if not 0 <= full_fraction <= 1:
        raise ValueError(f"full_fraction={full_fraction!r}: must be a fraction in [0, 1]")
    if not 0 < target < 1:
        raise ValueError(f"target={target!r}: must be a relative error in (0, 1)")
    if not sign > 0:
        raise ValueError(f"sign={sign!r}: must be a positive number of standard errors")
    scene = load_scene(scene)
    if not scene.sweep:
        raise ValueError("the scene has no [sweep]: a chaos map runs over a campaign's grid")
    if along is not None:
        if along not in scene.sweep:
            raise ValueError(
                f"along={along!r}: a map carries state along one of its swept parameters "
                f"{list(scene.sweep)!r}"
            )
        scene = scene.replace(
            sweep={**scene.sweep, "continuation": {"direction": "up", "along": along}}
        )
    measure = map_measurement(scene, full_fraction, full_seed, target, sign)
    if scene.continuation:
        if chunk is not None:
            raise ValueError(
                f"chunk={chunk!r}: a map along an axis runs in the continuation's segments "
                "(sweep.continuation.segments), not in chunks; drop chunk"
            )
        from workbench.continuation._sweep import continued_sweep

        maps = continued_sweep(
            scene,
            store,
            client=client,
            workers=workers,
            restart=restart,
            progress=progress,
            per_point=measure,
        )
    else:
        maps = run_campaign(
            scene,
            store,
            client=client,
            workers=workers,
            chunk=chunk,
            restart=restart,
            progress=progress,
            per_point=measure,
        )
    attrs = {
        "lle_full_fraction": float(full_fraction),
        "lle_full_seed": int(full_seed),
        "lle_target": float(target),
        "lle_sign": float(sign),
        **(subset_agreement(maps) if "lle_full_protocol" in maps else {}),
    }
    if any(k not in maps.attrs for k in attrs):  # a resumed, complete map has them already
        maps = maps.load()
        maps.close()
        maps.attrs.update(attrs)
        save_run(maps, store)
    return maps
