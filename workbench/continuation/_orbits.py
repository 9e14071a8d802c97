"""Periodic orbits of a forced scene: one orbit by shooting (``periodic_orbit``), and its
branch continued over a parameter with labelled bifurcations (``continue_orbit``)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import xarray as xr

from workbench._attributes import flag_meaning, flags, variable
from workbench.continuation._branch import (
    LABELS,
    MARGIN_TOLERANCE,
    MULTIPLIER_TOLERANCE,
    START_ITERATIONS,
    TRANSITIONS,
    BranchSettings,
    Traced,
    noisy_start,
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

LABEL_ATTRS = flags(
    "kind of the branch point",
    {v: k for k, v in LABELS.items()},
    comment="fold: a real multiplier through +1 where the parameter turns back; "
    "branch_point: through +1 without a turn; period_doubling: a real multiplier through -1; "
    "neimark_sacker: a complex pair leaves the unit circle; grazing: a local extremum of an "
    "event function along the orbit through zero (a contact appears or vanishes); "
    "nonsmooth_fold: the parameter turns back with no multiplier at +1 (the map is not smooth "
    "there) and det(M - I) changes sign across the turn (where it keeps its sign no fold of a "
    "continuous map turns there, and the turn is stored unresolved); each labelled only "
    "where its defining quantity confirms it (the critical "
    f"multiplier within {MULTIPLIER_TOLERANCE:g} of +1, -1 or the unit circle; the grazing "
    f"extremum within {MARGIN_TOLERANCE:g} of its event function's range); unresolved: a "
    "bifurcation bracketed but not confirmed (its suspected kind and bracket in the "
    "bifurcation_* variables)",
)


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
    cfg = BranchSettings(1.0, (-math.inf, math.inf), tolerance)
    pt = start_point(smap, y, aux, math.nan, cfg, max_iterations=int(max_iterations))
    tr = Traced(smap, [pt], ["start"], [complex(np.nan, np.nan)], "one orbit", smap.evaluations)
    tr.wall_time = time.perf_counter() - t0
    return _labelled(_computed([tr]), None, tolerance, max_iterations=int(max_iterations))


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
        ``1e-7 |stop - start|`` in the parameter. The map is integrated tighter at the start
        until its noise lies 10x below it (else it is raised); where the corrector fails
        further on and the map's noise there has outgrown it, it is raised to 10x that noise
        for the rest of the branch (attribute ``tolerance_raised``, at most 3 times).
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
    cfg = BranchSettings(
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
        first, raised_at_start = noisy_start(smap, y, aux, p0, cfg)
        smap, first, cfg.tolerance, noise = settle_noise(smap, first, cfg)
        direction = np.zeros(first.value.M.shape[0] + 1)
        direction[-1] = math.copysign(1.0, stop - p0)
        branches = [trace(smap, first, direction, cfg, report=report)]
        branches[0].raised[:0] = raised_at_start
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
    ds = _labelled(_computed(branches), parameter, cfg.tolerance, max_points=max_points)
    # every evaluation of the map and of the maps derived from it (one count): the start's
    # Newton, the noise check and the switches between branches included
    ds.attrs["map_evaluations"] = smap.evaluations
    ds.attrs["wall_time"] = time.perf_counter() - t0
    ds.attrs["tolerance_requested"] = tolerance
    ds.attrs["map_noise"] = noise
    raised = [r for b in branches for r in b.raised]
    if raised:  # the map's noise outgrew Newton's tolerance along a branch (_raise_to_noise)
        ds.attrs["tolerance_raised"] = "; ".join(
            f"at {p:.10g}: from {old:.3g} to {new:.3g} (the map's noise there {n:.3g}, scaled)"
            for p, old, new, n in raised
        )
    return ds


#: flags of ``bifurcation_transition``
TRANSITION_FLAGS = {"not_a_grazing": 0} | {t: i + 1 for i, t in enumerate(TRANSITIONS)}

METHOD = (
    "shooting on the stroboscopic map (Newton), monodromy matrix from the tangent system with "
    "saltation at events, pseudo-arclength continuation; bifurcations from the Floquet "
    "multipliers (det(M - I), det(M + I), complex multipliers outside the unit circle) and "
    "the events per period (grazing located on the extreme of an event function)"
)


@dataclass
class BranchNumbers:
    """The numbers of continued branches, computed and not yet labelled: arrays per point
    (``points``: first axis along the points of all branches, special points in their place),
    per point and event function (``contacts``; empty for a model without events) and per
    located bifurcation (``bifurcations``), each keyed by the name it is stored under
    (``parameter``: the continued parameter's values); the map of the first branch, the
    problem's public states and what each branch cost and why it ended.

    :func:`_computed` fills it (integrating the orbits again for their strobe samples and
    contact sequences); :func:`_labelled` names it."""

    smap: StrobeMap
    states: list
    points: dict[str, np.ndarray]
    contacts: dict[str, np.ndarray]
    bifurcations: dict[str, np.ndarray]
    evaluations: int
    wall_times: list[float]
    ended: list[str]
    notes: list[str]


def _computed(branches: list[Traced]) -> BranchNumbers:
    """The numbers of ``branches`` (:class:`BranchNumbers`)."""
    smap = branches[0].smap
    pb = smap.prepared(smap.value).problem
    states = [q for q in pb.states if not q.name.startswith("_")]
    index = {q.name: i for i, q in enumerate(pb.states)}
    rows = [
        (b, pt, lab)
        for b, tr in enumerate(branches)
        for pt, lab, _ in zip(tr.points, tr.labels, tr.critical, strict=True)
    ]
    n = len(rows)
    m = max(pt.value.M.shape[0] for _, pt, _ in rows)
    kmax = max(tr.smap.periods for tr in branches)
    mu = np.full((n, m), np.nan + 0j)
    strobe = {q.name: np.full((n, kmax), np.nan) for q in states}
    for i, (b, pt, _) in enumerate(rows):
        mult = pt.multipliers
        mu[i, : mult.size] = mult
        samples = branches[b].smap.orbit_samples(pt.y, pt.aux, pt.p)
        for q in states:
            strobe[q.name][i, : samples.shape[0]] = samples[:, index[q.name]]
    modulus = np.abs(mu)
    periods = np.array([branches[b].smap.periods for b, _, _ in rows], np.int32)
    points: dict[str, np.ndarray] = {}
    na, ne = pb.aux0.size, pb.event_direction.size
    if na:
        points["orbit_discrete_state"] = np.array([r[1].aux for r in rows], float).reshape(n, na)
    seqs = [sequence_of(branches[b].smap, pt) for b, pt, _ in rows] if ne else []
    points["parameter"] = np.array([r[1].p for r in rows])
    for q in states:
        points[f"orbit_{q.name}"] = np.array([r[1].y[index[q.name]] for r in rows])
        points[f"strobe_{q.name}"] = strobe[q.name]
    points["branch"] = np.array([r[0] for r in rows], np.int32)
    points["periods"] = periods
    points["multiplier_real"] = mu.real
    points["multiplier_imag"] = mu.imag
    points["multiplier_modulus"] = modulus
    points["stable"] = (np.nanmax(modulus, axis=1) < 1.0).astype(np.int8)
    points["events_per_period"] = np.array([r[1].value.events for r in rows]) / periods
    points["label"] = np.array([LABELS[r[2]] for r in rows], np.int8)
    points["newton_iterations"] = np.array([r[1].iterations for r in rows], np.int32)
    points["residual"] = np.array([r[1].residual for r in rows])
    specials = [(b, sp) for b, tr in enumerate(branches) for sp in tr.specials]
    row_of = {(b, id(pt)): i for i, (b, pt, _) in enumerate(rows)}
    crit = np.array([sp.critical for _, sp in specials], complex)
    transitions = [TRANSITION_FLAGS[sp.transition or "not_a_grazing"] for _, sp in specials]
    bifurcations = {
        "bifurcation_label": np.array([LABELS[sp.kind] for _, sp in specials], np.int8),
        "bifurcation_resolved": np.array([sp.resolved for _, sp in specials], np.int8),
        "bifurcation_branch": np.array([b for b, _ in specials], np.int32),
        "critical_real": crit.real,
        "critical_imag": crit.imag,
        "bifurcation_test": np.array([sp.test for _, sp in specials], float),
        "bifurcation_event": np.array([sp.event for _, sp in specials], np.int32),
        "bifurcation_phase": np.array([sp.phase for _, sp in specials], float),
        "bifurcation_transition": np.array(transitions, np.int8),
        "bifurcation_parameter": np.array([sp.point.p for _, sp in specials]),
        "bifurcation_lower": np.array([sp.lower for _, sp in specials]),
        "bifurcation_upper": np.array([sp.upper for _, sp in specials]),
        "bifurcation_point": np.array(
            [row_of.get((b, id(sp.point)), -1) for b, sp in specials], np.int32
        ),
    }
    return BranchNumbers(
        smap=smap,
        states=states,
        points=points,
        contacts=_contact_arrays(seqs, ne) if ne else {},
        bifurcations=bifurcations,
        evaluations=int(sum(tr.evaluations for tr in branches)),
        wall_times=[tr.wall_time for tr in branches],
        ended=[tr.ended for tr in branches],
        notes=[sp.note for tr in branches for sp in tr.specials],
    )


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


def _contact_arrays(seqs: list, ne: int) -> dict[str, np.ndarray]:
    """The contact sequence of every orbit (:mod:`workbench.continuation._contacts`) as arrays
    (point, event[, crossing or extremum])."""
    extrema = [list(q.extrema) for q in seqs]
    crossings = [list(q.crossings) for q in seqs]
    value = _padded(extrema, 1)
    kind = _padded(extrema, 2)
    return {
        "crossings_per_orbit": np.array([q.counts for q in seqs], np.int32).reshape(len(seqs), ne),
        "crossing_phase": _padded(crossings, 0),
        "extremum_phase": _padded(extrema, 0),
        "extremum_value": value,
        "extremum_kind": kind,
        "event_max": _extreme_of(np.where(kind == 1.0, value, np.nan), np.max),
        "event_min": _extreme_of(np.where(kind == -1.0, value, np.nan), np.min),
    }


def _labelled(
    numbers: BranchNumbers,
    parameter: str | None,
    tolerance: float,
    *,
    max_points: int | None = None,
    max_iterations: int | None = None,
) -> xr.Dataset:
    """The branches' numbers as one dataset (layout: :func:`continue_orbit`); the attributes
    ``max_points`` (of a branch) and ``max_iterations`` (of one orbit) where given."""
    smap, points, bif = numbers.smap, numbers.points, numbers.bifurcations
    model = get_model(smap.scene.model)
    data: dict = {}
    if "orbit_discrete_state" in points:
        data["orbit_discrete_state"] = (
            ("point", "discrete_state"),
            points["orbit_discrete_state"],
            variable(
                "the model's discrete state on the orbit at the strobe time (the mechanisms: "
                "each joint's contact onset velocity, held through a lasting contact: a "
                "constant of such an orbit that sets its contact damping)",
                model.discrete_state_units,
            ),
        )
    data.update(_contact_variables(numbers.contacts, model.event_units))
    if parameter is not None:
        par = model.parameter(parameter)
        p_attrs = variable(par.long_name, par.units)
        data[parameter] = ("point", points["parameter"], p_attrs)
    for q in numbers.states:
        long_name = f"{q.long_name} on the orbit at the strobe time"
        data[f"orbit_{q.name}"] = ("point", points[f"orbit_{q.name}"], variable(long_name, q.units))
        long_name = f"{q.long_name} at the orbit's strobe times"
        name = f"strobe_{q.name}"
        data[name] = (("point", "sample"), points[name], variable(long_name, q.units))
    pm = ("point", "multiplier")
    labels = {
        "branch": ("point", variable("branch index (b + 1 switched from b)")),
        "periods": ("point", variable("period of the orbit in forcing periods")),
        "multiplier_real": (pm, variable("real part of a Floquet multiplier")),
        "multiplier_imag": (pm, variable("imaginary part of a Floquet multiplier")),
        "multiplier_modulus": (pm, variable("modulus of a Floquet multiplier")),
        "stable": (
            "point",
            flags("all Floquet multipliers inside the unit circle", ["unstable", "stable"]),
        ),
        "events_per_period": (
            "point",
            variable("events located per forcing period (the mechanisms: contact onsets and ends)"),
        ),
        "label": ("point", LABEL_ATTRS),
        "newton_iterations": ("point", variable("Newton iterations of the point")),
        "residual": ("point", variable("scaled residual max |P^k(x) - x| / s")),
    }
    for name, (dims, attrs) in labels.items():
        data[name] = (dims, points[name], attrs)
    for name, attrs in _bifurcation_attrs(model, p_attrs if parameter else None).items():
        data[name] = ("bifurcation", bif[name], attrs)
    n, m = points["multiplier_real"].shape
    coords = {
        "point": ("point", np.arange(n), variable("index along the branches")),
        "multiplier": ("multiplier", np.arange(m), variable("multiplier (largest modulus first)")),
        "sample": (
            "sample",
            np.arange(int(points["periods"].max())),
            variable("strobe sample of the orbit (k T on)"),
        ),
        "bifurcation": (
            "bifurcation",
            np.arange(bif["bifurcation_label"].size),
            variable("located bifurcation"),
        ),
    }
    if "orbit_discrete_state" in points:
        na = points["orbit_discrete_state"].shape[1]
        coords["discrete_state"] = ("discrete_state", np.arange(na), variable("discrete state"))
    if numbers.contacts:
        ne = numbers.contacts["crossings_per_orbit"].shape[1]
        coords["event"] = ("event", np.arange(ne), variable("event function"))
        coords["extremum"] = (
            "extremum",
            np.arange(numbers.contacts["extremum_value"].shape[2]),
            variable("local extremum of an event function along the orbit, in order of phase"),
        )
        coords["crossing"] = (
            "crossing",
            np.arange(numbers.contacts["crossing_phase"].shape[2]),
            variable("crossing of an event function in its direction, in order of phase"),
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
        map_evaluations=numbers.evaluations,
        branch_wall_time=" ".join(f"{t:.6g}" for t in numbers.wall_times),
        branch_ended=" | ".join(e or "-" for e in numbers.ended),
        bifurcation_notes=" | ".join(note or "-" for note in numbers.notes),
    )
    if max_points is not None:
        ds.attrs["max_points"] = max_points
    if max_iterations is not None:
        ds.attrs["max_iterations"] = max_iterations
    return ds


def _contact_variables(contacts: dict[str, np.ndarray], units: str) -> dict:
    """The contact sequences' arrays (:func:`_contact_arrays`) labelled; ``units`` those of the
    event functions."""
    if not contacts:
        return {}
    pe, pex, pc = ("point", "event"), ("point", "event", "extremum"), ("point", "event", "crossing")
    labels = {
        "crossings_per_orbit": (
            pe,
            variable(
                "crossings of each event function in its direction along the orbit (the "
                "mechanisms: contact onsets for events 2i, ends for events 2i + 1)"
            ),
        ),
        "crossing_phase": (pc, variable("time of each crossing after the strobe time", "s")),
        "extremum_phase": (
            pex,
            variable(
                "time of each local extremum of the event function after the strobe time", "s"
            ),
        ),
        "extremum_value": (
            pex,
            variable(
                "value of the event function at each of its local extrema: the margin to the "
                "next grazing (a maximum below 0: a free flight that misses the surface by so "
                "much; a minimum above 0: a lasting contact that stays on by so much)",
                units,
            ),
        ),
        "extremum_kind": (
            pex,
            flags("kind of the local extremum", {-1.0: "minimum", 1.0: "maximum"}, dtype=float),
        ),
        "event_max": (
            pe,
            variable(
                "largest value of each event function along the orbit (crosses 0 where a contact "
                "appears: grazing); the mechanisms: a joint's penetration, events 2i and 2i + 1 "
                "of its i-th clearance joint",
                units,
            ),
        ),
        "event_min": (
            pe,
            variable(
                "smallest value of each event function along the orbit (crosses 0 where a "
                "lasting contact lifts off)",
                units,
            ),
        ),
    }
    return {name: (dims, contacts[name], attrs) for name, (dims, attrs) in labels.items()}


def _bifurcation_attrs(model, p_attrs: dict | None) -> dict[str, dict]:
    """The attributes of the bifurcations' variables (dim ``bifurcation``), each with its
    bracket and the quantity that confirms it; the parameter's (``p_attrs``) when continued
    over one."""
    long_name = "part of the multiplier that crossed the unit circle"
    out = {
        "bifurcation_label": dict(
            LABEL_ATTRS, long_name="kind of the bifurcation (suspected, where unresolved)"
        ),
        "bifurcation_resolved": flags(
            "located and confirmed by its defining quantity (1), or only bracketed (0)",
            ["unresolved", "resolved"],
        ),
        "bifurcation_branch": variable("branch index of the bifurcation"),
        "critical_real": variable(f"real {long_name}"),
        "critical_imag": variable(f"imaginary {long_name}"),
        "bifurcation_test": variable(
            "the defining quantity at the located point: the critical multiplier's "
            "distance from +1, -1 or the unit circle (1); for a grazing the extremum's "
            f"value ({model.event_units})"
        ),
        "bifurcation_event": variable("event function of a grazing (-1: not a grazing)"),
        "bifurcation_phase": variable("time after the strobe time of a grazing's extremum", "s"),
        "bifurcation_transition": flags(
            "how the orbit passes a grazing: persistent (it crosses with the new contact), "
            "nonsmooth_fold (the branch turns at it), border_collision (no orbit of the "
            "branch's period past it: the period there in the note), not_typed, "
            "persistent_flip (it crosses, and a real multiplier jumps across -1 there: "
            "Feigin's counts of real multipliers below -1 on the two sides, with the period "
            "doublings located between them, sum to an odd number; a period-2 orbit is born "
            "in a continuous piecewise-smooth map, di Bernardo, Feigin, Hogan & Homer 1999)",
            {v: k for k, v in TRANSITION_FLAGS.items()},
        ),
    }
    if p_attrs is not None:
        out["bifurcation_parameter"] = dict(p_attrs)
        for name in ("lower", "upper"):
            out[f"bifurcation_{name}"] = dict(
                p_attrs, long_name=f"{p_attrs['long_name']} at the {name} end of the bracket"
            )
    out["bifurcation_point"] = variable("index along point of the bifurcation's located orbit")
    return out


def branch_bifurcations(branch: xr.Dataset, parameter: str) -> list[dict]:
    """The bifurcations located on a branch of :func:`continue_orbit`, in order: per
    bifurcation its ``type`` (the label's meaning, e.g. ``period_doubling``), ``value`` (the
    parameter there, in its units), ``critical`` (the critical Floquet multiplier, complex),
    ``index`` (the branch point nearest to it), ``resolved`` (False: only bracketed, the
    defining quantity did not confirm the kind) and, for a grazing, ``transition`` (how the
    orbit passes it, a key of ``TRANSITION_FLAGS``; ``"not_a_grazing"`` for the others)."""
    values = branch[parameter].values
    count = branch.sizes.get("bifurcation", 0)
    if "bifurcation_transition" in branch:
        transition = branch.bifurcation_transition
        transitions = [flag_meaning(transition, c) for c in transition.values]
    else:  # an archive written before transitions were typed
        transitions = ["not_typed"] * count
    return [
        {
            "type": flag_meaning(branch.label, k),
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
