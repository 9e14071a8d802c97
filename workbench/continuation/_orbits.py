"""Periodic orbits of a forced scene: one orbit by shooting (``periodic_orbit``), and its
branch continued over a parameter with labelled bifurcations (``continue_orbit``)."""

from __future__ import annotations

import math
import time

import numpy as np
import xarray as xr

from workbench.continuation._branch import (
    LABELS,
    MARGIN_TOLERANCE,
    MULTIPLIER_TOLERANCE,
    START_ITERATIONS,
    TRANSITIONS,
    Settings,
    Traced,
    sequence_of,
    settle_noise,
    start_point,
    switch_at_doubling,
    trace,
)
from workbench.continuation._newton import NewtonFailure
from workbench.continuation._report import RangeProgress
from workbench.continuation._strobe import StrobeMap
from workbench.models import get_model
from workbench.run import provenance
from workbench.scene import SceneSource, load_scene

__all__ = ["continue_orbit", "periodic_orbit"]

LABEL_ATTRS = {
    "long_name": "kind of the branch point",
    "units": "1",
    "flag_values": np.array(list(LABELS.values()), np.int8),
    "flag_meanings": " ".join(LABELS),
    "comment": "fold: a real multiplier through +1 where the parameter turns back; "
    "branch_point: through +1 without a turn; period_doubling: a real multiplier through -1; "
    "neimark_sacker: a complex pair leaves the unit circle; grazing: a local extremum of an "
    "event function along the orbit through zero (a contact appears or vanishes); "
    "nonsmooth_fold: the parameter turns back with no multiplier at +1 (the map is not smooth "
    "there); each labelled only where its defining quantity confirms it (the critical "
    f"multiplier within {MULTIPLIER_TOLERANCE:g} of +1, -1 or the unit circle; the grazing "
    f"extremum within {MARGIN_TOLERANCE:g} of its event function's range); unresolved: a "
    "bifurcation bracketed but not confirmed (its suspected kind and bracket in the "
    "bifurcation_* variables)",
}


def _guess(smap: StrobeMap, p: float, state, aux, transient: int | None):
    if state is None:
        return smap.initial(p, transient)
    pb = smap.prepared(p).problem
    names = [q.name for q in pb.states]
    if isinstance(state, dict):
        y = pb.y0.copy()
        for k, v in state.items():
            if k not in names:
                raise ValueError(f"state: unknown state {k!r}; the states are {names!r}")
            y[names.index(k)] = float(v)
    else:
        y = np.asarray(state, dtype=float)
        if y.shape != pb.y0.shape:
            raise ValueError(f"state: expected {pb.y0.size} values ({names}), got {y.shape}")
    a = pb.aux0.copy() if aux is None else np.asarray(aux, dtype=float)
    return y, a


def periodic_orbit(
    scene: SceneSource,
    *,
    periods: int = 1,
    state=None,
    discrete_state=None,
    tolerance: float = 1e-8,
    max_iterations: int = START_ITERATIONS,
    rtol: float | None = None,
    monodromy: str = "auto",
) -> xr.Dataset:
    """A period-``k`` orbit of a forced scene's stroboscopic map, stable or not, by Newton's
    method (shooting) with the monodromy matrix of the tangent system (saltation at events),
    and its Floquet multipliers.

    Parameters
    ----------
    scene : Scene, path or mapping
        A forced model at the parameter values of the orbit.
    periods : int
        ``k``: the orbit's period in forcing periods.
    state : mapping or array, optional
        Start of Newton's method (state units; a mapping of state names, or the whole state).
        Default: the state after the scene's ``run.transient_cycles`` from its initial state.
    discrete_state : array, optional
        The discrete state to start from (default the model's initial one, or the transient's).
    tolerance : float
        Newton stops when the scaled residual ``max |P^k(x) - x| / s`` is below this.
    max_iterations : int
        Newton's iterations at most (0: only check that the start is an orbit within
        ``tolerance``); each costs one evaluation of the map and its Jacobian.
    rtol : float, optional
        Integration tolerance (default ``min(scene rtol, 1e-9)``).
    monodromy : str
        How the map's Jacobian is computed: ``"tangent"`` (the tangent system with saltation),
        ``"copies"`` (central differences of copies in one step sequence) or ``"auto"``
        (tangent for a model with an analytic Jacobian; :mod:`workbench.continuation._strobe`).

    Returns
    -------
    xarray.Dataset
        One point of :func:`continue_orbit`'s layout (dim ``point`` of size 1); attributes
        ``tolerance`` and ``max_iterations`` as given (``newton_iterations`` says how many it
        took).

    Raises
    ------
    ValueError
        ``max_iterations`` is not a non-negative integer.
    RuntimeError
        Newton's method did not reach ``tolerance`` within ``max_iterations`` iterations (the
        message gives the residual reached), or the map failed on the way.

    Examples
    --------
    >>> r = periodic_orbit({"model": {"name": "duffing"}, "parameters": {"gamma": 0.2},
    ...                     "run": {"transient_cycles": 50}})
    >>> bool(r.stable[0]), int(r.newton_iterations[0]) <= 5
    (True, True)
    """
    integer = isinstance(max_iterations, int | np.integer) and not isinstance(max_iterations, bool)
    if not integer or max_iterations < 0:
        raise ValueError(
            f"max_iterations={max_iterations!r}: must be a non-negative integer (Newton's "
            "iterations at most)"
        )
    smap = StrobeMap(scene, None, periods=periods, rtol=rtol, monodromy=monodromy)
    t0 = time.perf_counter()
    y, aux = _guess(smap, math.nan, state, discrete_state, None)
    cfg = Settings(1.0, (-math.inf, math.inf), tolerance)
    pt = start_point(smap, y, aux, math.nan, cfg, max_iterations=int(max_iterations))
    tr = Traced(smap, [pt], ["start"], [complex(np.nan, np.nan)], "one orbit", pt.evaluations)
    tr.wall_time = time.perf_counter() - t0
    return _dataset([tr], None, tolerance, max_iterations=int(max_iterations))


def continue_orbit(
    scene: SceneSource,
    parameter: str,
    *,
    stop: float,
    start: float | None = None,
    periods: int = 1,
    state=None,
    discrete_state=None,
    doublings: int = 0,
    tolerance: float = 1e-8,
    step: float = 0.02,
    max_step: float = 0.05,
    max_points: int = 300,
    rtol: float | None = None,
    monodromy: str = "auto",
    progress: bool = False,
) -> xr.Dataset:
    """Continue a branch of period-``k`` orbits over ``parameter`` by pseudo-arclength (so it
    passes folds), with Floquet multipliers at every point and its bifurcations detected,
    located and labelled (fold, branch point, period doubling, Neimark-Sacker, grazing);
    optionally switching to the doubled branch at the first period doubling, ``doublings``
    times (a cascade).

    Parameters
    ----------
    scene : Scene, path or mapping
        A forced model; its other parameters are fixed.
    parameter : str
        The model parameter to continue in (SI units).
    stop : float
        The branch is followed until the parameter leaves the range between ``start`` and
        ``stop`` (also after a fold turns it back).
    start : float, optional
        Where the branch starts (default the scene's value).
    periods : int
        ``k`` of the first branch.
    state, discrete_state : optional
        Newton's start at ``start`` (see :func:`periodic_orbit`; default after the scene's
        transient).
    doublings : int
        How many times to switch to the doubled branch at the first period doubling found on
        the current branch.
    tolerance : float
        Newton's tolerance on the scaled residual; bifurcations are located to
        ``1e-7 |stop - start|`` in the parameter.
    step, max_step : float
        First and largest arclength step, in scaled units (states by their characteristic
        sizes, the parameter by ``|stop - start|``).
    max_points : int
        Points per branch at most.
    rtol : float, optional
        Integration tolerance (default ``min(scene rtol, 1e-9)``).
    monodromy : str
        ``"tangent"``, ``"copies"`` or ``"auto"`` (see :func:`periodic_orbit`).
    progress : bool
        Show on stderr how much of the range each branch has covered, and where it is
        (:class:`workbench._progress.Progress`: a bar on a terminal, a few lines in a log).

    Returns
    -------
    xarray.Dataset
        Dim ``point`` along the branches (special points in their place), ``multiplier``
        (largest modulus first) and ``sample`` (the ``k`` strobe states of an orbit):
        the parameter (named after it, with its units), ``orbit_<state>`` (the orbit's state at
        the strobe time, state units), ``strobe_<state>`` (point, sample), ``branch`` and
        ``periods`` per point, ``multiplier_real``, ``multiplier_imag`` and
        ``multiplier_modulus`` (1), ``stable`` (all inside the unit circle),
        ``events_per_period``, ``label`` (CF flags: regular, start, end, fold, branch_point,
        period_doubling, neimark_sacker, grazing, nonsmooth_fold), ``newton_iterations``,
        ``residual``; for a model with a discrete state ``orbit_discrete_state`` (point,
        discrete_state; the mechanisms: held contact onset velocities, m s-1), with events
        ``event_max`` and ``event_min`` (point, event: the largest and smallest value of each
        event function along the orbit; the mechanisms: penetration, m; the largest crosses 0
        where a contact appears, the smallest where a lasting one lifts off); and
        per located bifurcation (dim ``bifurcation``): ``bifurcation_parameter``,
        ``bifurcation_label``, ``bifurcation_branch``, ``critical_real`` and
        ``critical_imag`` (the multiplier that crossed). Attributes: the scene, the cost
        (map evaluations, wall time), why each branch ended.

    Examples
    --------
    >>> r = continue_orbit({"model": {"name": "duffing"}, "parameters": {"gamma": 0.25},
    ...                     "run": {"transient_cycles": 100}}, "gamma", stop=0.27)
    >>> [round(float(g), 3) for g in r.bifurcation_parameter]   # the first period doubling
    [0.266]
    """
    base = load_scene(scene)
    smap = StrobeMap(base, parameter, periods=periods, rtol=rtol, monodromy=monodromy)
    p0 = smap.value if start is None else float(start)
    stop = float(stop)
    if not (math.isfinite(stop) and stop != p0):
        raise ValueError(f"stop={stop!r}: must be a finite value other than start ({p0!r})")
    pscale = abs(stop - p0)
    cfg = Settings(
        pscale=pscale,
        bounds=(min(p0, stop), max(p0, stop)),
        tolerance=tolerance,
        step=step,
        max_step=max_step,
        max_points=max_points,
    )
    report = RangeProgress(progress, parameter, p0, stop, "branch")
    try:  # the first orbit (after the transient) is part of the first branch's progress
        y, aux = _guess(smap, p0, state, discrete_state, None)
        t0 = time.perf_counter()
        first = start_point(smap, y, aux, p0, cfg)
        smap, first, cfg.tolerance, noise = settle_noise(smap, first, cfg)
        direction = np.zeros(first.value.M.shape[0] + 1)
        direction[-1] = math.copysign(1.0, stop - p0)
        branches = [trace(smap, first, direction, cfg, report=report)]
    finally:
        report.close()
    for _ in range(doublings):
        last = branches[-1]
        pd = [
            p for p, lab in zip(last.points, last.labels, strict=True) if lab == "period_doubling"
        ]
        if not pd:
            break
        try:
            double, pt, away = switch_at_doubling(last.smap, pd[0], cfg)
        except NewtonFailure as exc:
            last.ended += f"; switching at the period doubling failed ({exc})"
            break
        report = RangeProgress(progress, parameter, pt.p, stop, f"branch {len(branches) + 1}")
        try:
            branches.append(trace(double, pt, away, cfg, label="start", report=report))
        finally:
            report.close()
    ds = _dataset(branches, parameter, cfg.tolerance, max_points=max_points)
    ds.attrs["wall_time"] = time.perf_counter() - t0
    ds.attrs["tolerance_requested"] = tolerance
    ds.attrs["map_noise"] = noise
    return ds


#: flags of ``bifurcation_transition``
TRANSITION_FLAGS = {"not_a_grazing": 0} | {t: i + 1 for i, t in enumerate(TRANSITIONS)}


def _attrs(long_name: str, units: str = "1", **extra) -> dict:
    return {"long_name": long_name, "units": units, **extra}


METHOD = (
    "shooting on the stroboscopic map (Newton), monodromy matrix from the tangent system with "
    "saltation at events, pseudo-arclength continuation; bifurcations from the Floquet "
    "multipliers (det(M - I), det(M + I), complex multipliers outside the unit circle) and "
    "the events per period (grazing located on the extreme of an event function)"
)


def _dataset(
    branches: list[Traced],
    parameter: str | None,
    tolerance: float,
    *,
    max_points: int | None = None,
    max_iterations: int | None = None,
) -> xr.Dataset:
    """The branches as one dataset (layout: :func:`continue_orbit`); the attributes
    ``max_points`` (of a branch) and ``max_iterations`` (of one orbit) where given."""
    smap = branches[0].smap
    pb = smap.prepared(smap.value).problem
    states = [q for q in pb.states if not q.name.startswith("_")]
    index = {q.name: i for i, q in enumerate(pb.states)}
    rows = [
        (b, pt, lab, crit)
        for b, tr in enumerate(branches)
        for pt, lab, crit in zip(tr.points, tr.labels, tr.critical, strict=True)
    ]
    n = len(rows)
    m = max(pt.value.M.shape[0] for _, pt, _, _ in rows)
    kmax = max(tr.smap.periods for tr in branches)
    mu = np.full((n, m), np.nan + 0j)
    strobe = {q.name: np.full((n, kmax), np.nan) for q in states}
    for i, (b, pt, _, _) in enumerate(rows):
        mult = pt.multipliers
        mu[i, : mult.size] = mult
        samples = branches[b].smap.orbit_samples(pt.y, pt.aux, pt.p)
        for q in states:
            strobe[q.name][i, : samples.shape[0]] = samples[:, index[q.name]]
    modulus = np.abs(mu)
    periods = np.array([branches[b].smap.periods for b, _, _, _ in rows], np.int32)
    model = get_model(smap.scene.model)
    data: dict = {}
    na, ne = pb.aux0.size, pb.event_direction.size
    if na:
        held = np.array([r[1].aux for r in rows], dtype=float).reshape(n, na)
        data["orbit_discrete_state"] = (
            ("point", "discrete_state"),
            held,
            _attrs(
                "the model's discrete state on the orbit at the strobe time (the mechanisms: "
                "each joint's contact onset velocity, held through a lasting contact: a "
                "constant of such an orbit that sets its contact damping)",
                model.discrete_state_units,
            ),
        )
    if ne:
        seqs = [sequence_of(branches[b].smap, pt) for b, pt, _, _ in rows]
        data.update(_sequence_variables(seqs, ne, model.event_units))
    if parameter is not None:
        par = get_model(smap.scene.model).parameter(parameter)
        p_attrs = _attrs(par.long_name, par.units)
        data[parameter] = ("point", np.array([r[1].p for r in rows]), p_attrs)
    for q in states:
        y = np.array([r[1].y[index[q.name]] for r in rows])
        long_name = f"{q.long_name} on the orbit at the strobe time"
        data[f"orbit_{q.name}"] = ("point", y, _attrs(long_name, q.units))
        long_name = f"{q.long_name} at the orbit's strobe times"
        data[f"strobe_{q.name}"] = (("point", "sample"), strobe[q.name], _attrs(long_name, q.units))
    branch = np.array([r[0] for r in rows], np.int32)
    data["branch"] = ("point", branch, _attrs("branch index (b + 1 switched from b)"))
    data["periods"] = ("point", periods, _attrs("period of the orbit in forcing periods"))
    pm = ("point", "multiplier")
    data["multiplier_real"] = (pm, mu.real, _attrs("real part of a Floquet multiplier"))
    data["multiplier_imag"] = (pm, mu.imag, _attrs("imaginary part of a Floquet multiplier"))
    data["multiplier_modulus"] = (pm, modulus, _attrs("modulus of a Floquet multiplier"))
    stable = (np.nanmax(modulus, axis=1) < 1.0).astype(np.int8)
    data["stable"] = (
        "point",
        stable,
        _attrs(
            "all Floquet multipliers inside the unit circle",
            flag_values=np.array([0, 1], np.int8),
            flag_meanings="unstable stable",
        ),
    )
    events = np.array([r[1].value.events for r in rows]) / periods
    data["events_per_period"] = (
        "point",
        events,
        _attrs("events located per forcing period (the mechanisms: contact onsets and ends)"),
    )
    data["label"] = ("point", np.array([LABELS[r[2]] for r in rows], np.int8), LABEL_ATTRS)
    iterations = np.array([r[1].iterations for r in rows], np.int32)
    data["newton_iterations"] = ("point", iterations, _attrs("Newton iterations of the point"))
    residual = np.array([r[1].residual for r in rows])
    data["residual"] = ("point", residual, _attrs("scaled residual max |P^k(x) - x| / s"))
    specials = [(b, sp) for b, tr in enumerate(branches) for sp in tr.specials]
    row_of = {(b, id(pt)): i for i, (b, pt, _, _) in enumerate(rows)}
    data.update(_special_variables(specials, parameter, p_attrs if parameter else None, model))
    data["bifurcation_point"] = (
        "bifurcation",
        np.array([row_of.get((b, id(sp.point)), -1) for b, sp in specials], np.int32),
        _attrs("index along point of the bifurcation's located orbit"),
    )
    coords = {
        "point": ("point", np.arange(n), _attrs("index along the branches")),
        "multiplier": ("multiplier", np.arange(m), _attrs("multiplier (largest modulus first)")),
        "sample": ("sample", np.arange(kmax), _attrs("strobe sample of the orbit (k T on)")),
        "bifurcation": ("bifurcation", np.arange(len(specials)), _attrs("located bifurcation")),
    }
    if na:
        coords["discrete_state"] = ("discrete_state", np.arange(na), _attrs("discrete state"))
    if ne:
        coords["event"] = ("event", np.arange(ne), _attrs("event function"))
        coords["extremum"] = (
            "extremum",
            np.arange(data["extremum_value"][1].shape[2]),
            _attrs("local extremum of an event function along the orbit, in order of phase"),
        )
        coords["crossing"] = (
            "crossing",
            np.arange(data["crossing_phase"][1].shape[2]),
            _attrs("crossing of an event function in its direction, in order of phase"),
        )
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(provenance(smap.scene, by="workbench.continuation.continue_orbit"))
    title = f"periodic orbits of model {smap.scene.model}"
    ds.attrs.update(
        title=title + (f" continued over {parameter}" if parameter else ""),
        continuation_parameter=parameter or "",
        method=METHOD,
        monodromy=smap.monodromy,
        integration_method=smap.method,
        scene_method=smap.scene_method,
        rtol=smap.rtol,
        tolerance=tolerance,
        map_evaluations=int(sum(tr.evaluations for tr in branches)),
        branch_wall_time=" ".join(f"{tr.wall_time:.6g}" for tr in branches),
        branch_ended=" | ".join(tr.ended or "-" for tr in branches),
        bifurcation_notes=" | ".join(sp.note or "-" for tr in branches for sp in tr.specials),
    )
    if max_points is not None:
        ds.attrs["max_points"] = max_points
    if max_iterations is not None:
        ds.attrs["max_iterations"] = max_iterations
    return ds


def _padded(arrays: list[list[np.ndarray]], column: int) -> np.ndarray:
    """(point, event, item) array of one column of per-point, per-event rows, NaN-padded."""
    width = max([1] + [a.shape[0] for per in arrays for a in per])
    out = np.full((len(arrays), len(arrays[0]) if arrays else 0, width), np.nan)
    for i, per in enumerate(arrays):
        for k, a in enumerate(per):
            out[i, k, : a.shape[0]] = a[:, column] if a.ndim == 2 else a
    return out


def _extreme_of(a: np.ndarray, pick) -> np.ndarray:
    """``pick`` (np.max or np.min) over the last axis, ignoring NaN (NaN where all are)."""
    fill = -np.inf if pick is np.max else np.inf
    out = pick(np.where(np.isnan(a), fill, a), axis=-1)
    return np.where(np.isinf(out), np.nan, out)


def _sequence_variables(seqs: list, ne: int, units: str) -> dict:
    """The contact sequence of every orbit (:mod:`workbench.continuation._contacts`)."""
    extrema = [list(q.extrema) for q in seqs]
    crossings = [list(q.crossings) for q in seqs]
    value = _padded(extrema, 1)
    kind = _padded(extrema, 2)
    pe, pex, pc = ("point", "event"), ("point", "event", "extremum"), ("point", "event", "crossing")
    return {
        "crossings_per_orbit": (
            pe,
            np.array([q.counts for q in seqs], np.int32).reshape(len(seqs), ne),
            _attrs(
                "crossings of each event function in its direction along the orbit (the "
                "mechanisms: contact onsets for events 2i, ends for events 2i + 1)"
            ),
        ),
        "crossing_phase": (
            pc,
            _padded(crossings, 0),
            _attrs("time of each crossing after the strobe time", "s"),
        ),
        "extremum_phase": (
            pex,
            _padded(extrema, 0),
            _attrs("time of each local extremum of the event function after the strobe time", "s"),
        ),
        "extremum_value": (
            pex,
            value,
            _attrs(
                "value of the event function at each of its local extrema: the margin to the "
                "next grazing (a maximum below 0: a free flight that misses the surface by so "
                "much; a minimum above 0: a lasting contact that stays on by so much)",
                units,
            ),
        ),
        "extremum_kind": (
            pex,
            kind,
            _attrs(
                "kind of the local extremum",
                flag_values=np.array([-1.0, 1.0]),
                flag_meanings="minimum maximum",
            ),
        ),
        "event_max": (
            pe,
            _extreme_of(np.where(kind == 1.0, value, np.nan), np.max),
            _attrs(
                "largest value of each event function along the orbit (crosses 0 where a contact "
                "appears: grazing); the mechanisms: a joint's penetration, events 2i and 2i + 1 "
                "of its i-th clearance joint",
                units,
            ),
        ),
        "event_min": (
            pe,
            _extreme_of(np.where(kind == -1.0, value, np.nan), np.min),
            _attrs(
                "smallest value of each event function along the orbit (crosses 0 where a "
                "lasting contact lifts off)",
                units,
            ),
        ),
    }


def _special_variables(specials: list, parameter: str | None, p_attrs, model) -> dict:
    """The bifurcations of the branches, each with its bracket and the quantity that confirms
    it (dim ``bifurcation``)."""
    kinds = np.array([LABELS[sp.kind] for _, sp in specials], np.int8)
    crit = np.array([sp.critical for _, sp in specials], complex)
    long_name = "part of the multiplier that crossed the unit circle"
    out = {
        "bifurcation_label": (
            "bifurcation",
            kinds,
            dict(LABEL_ATTRS, long_name="kind of the bifurcation (suspected, where unresolved)"),
        ),
        "bifurcation_resolved": (
            "bifurcation",
            np.array([sp.resolved for _, sp in specials], np.int8),
            _attrs(
                "located and confirmed by its defining quantity (1), or only bracketed (0)",
                flag_values=np.array([0, 1], np.int8),
                flag_meanings="unresolved resolved",
            ),
        ),
        "bifurcation_branch": (
            "bifurcation",
            np.array([b for b, _ in specials], np.int32),
            _attrs("branch index of the bifurcation"),
        ),
        "critical_real": ("bifurcation", crit.real, _attrs(f"real {long_name}")),
        "critical_imag": ("bifurcation", crit.imag, _attrs(f"imaginary {long_name}")),
        "bifurcation_test": (
            "bifurcation",
            np.array([sp.test for _, sp in specials], float),
            _attrs(
                "the defining quantity at the located point: the critical multiplier's "
                "distance from +1, -1 or the unit circle (1); for a grazing the extremum's "
                f"value ({model.event_units})"
            ),
        ),
        "bifurcation_event": (
            "bifurcation",
            np.array([sp.event for _, sp in specials], np.int32),
            _attrs("event function of a grazing (-1: not a grazing)"),
        ),
        "bifurcation_phase": (
            "bifurcation",
            np.array([sp.phase for _, sp in specials], float),
            _attrs("time after the strobe time of a grazing's extremum", "s"),
        ),
        "bifurcation_transition": (
            "bifurcation",
            np.array(
                [TRANSITION_FLAGS[sp.transition or "not_a_grazing"] for _, sp in specials],
                np.int8,
            ),
            _attrs(
                "how the orbit passes a grazing: persistent (it crosses with the new contact), "
                "nonsmooth_fold (the branch turns at it), border_collision (no orbit of the "
                "branch's period past it: the period there in the note), not_typed",
                flag_values=np.array(list(TRANSITION_FLAGS.values()), np.int8),
                flag_meanings=" ".join(TRANSITION_FLAGS),
            ),
        ),
    }
    if parameter is not None:
        out["bifurcation_parameter"] = (
            "bifurcation",
            np.array([sp.point.p for _, sp in specials]),
            dict(p_attrs),
        )
        for name, pick in (("lower", lambda sp: sp.lower), ("upper", lambda sp: sp.upper)):
            out[f"bifurcation_{name}"] = (
                "bifurcation",
                np.array([pick(sp) for _, sp in specials]),
                dict(p_attrs, long_name=f"{p_attrs['long_name']} at the {name} end of the bracket"),
            )
    return out


def branch_bifurcations(branch: xr.Dataset, parameter: str) -> list[dict]:
    """The bifurcations located on a branch of :func:`continue_orbit`, in order: per
    bifurcation its ``type`` (the label's meaning, e.g. ``period_doubling``), ``value`` (the
    parameter there, in its units), ``critical`` (the critical Floquet multiplier, complex),
    ``index`` (the branch point nearest to it), ``resolved`` (False: only bracketed, the
    defining quantity did not confirm the kind) and, for a grazing, ``transition`` (how the
    orbit passes it, a key of ``TRANSITION_FLAGS``; ``"not_a_grazing"`` for the others)."""
    names = branch.label.attrs["flag_meanings"].split()
    values = branch[parameter].values
    count = branch.sizes.get("bifurcation", 0)
    if "bifurcation_transition" in branch:
        kinds = branch.bifurcation_transition.attrs["flag_meanings"].split()
        codes = list(branch.bifurcation_transition.attrs["flag_values"])
        transitions = [kinds[codes.index(int(c))] for c in branch.bifurcation_transition.values]
    else:  # an archive written before transitions were typed
        transitions = ["not_typed"] * count
    return [
        {
            "type": names[int(k)],
            "value": float(p),
            "critical": complex(re, im),
            "index": int(np.argmin(np.abs(values - p))),
            "resolved": bool(ok),
            "transition": tr,
        }
        for k, p, re, im, ok, tr in zip(
            branch.bifurcation_label.values,
            branch.bifurcation_parameter.values,
            branch.critical_real.values,
            branch.critical_imag.values,
            branch.bifurcation_resolved.values,
            transitions,
            strict=True,
        )
    ]
