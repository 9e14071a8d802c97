"""Linear stability: eigenvalues of a model's Jacobian along a run, and the Floquet multipliers
of a periodic orbit of a forced model from its monodromy matrix (the tangent map over whole
forcing periods, with saltation at events).

The eigenvalues of the Jacobian at a state are the local rates of the linearised flow there
(s-1): a complex pair with a positive real part is a growing oscillation, e.g. the
friction-induced mode coupling (flutter) of a sliding contact (Hoffmann, Fischer, Allgaier &
Gaul 2002, Mech. Res. Commun. 29, 197). The Floquet multipliers of a periodic orbit are the
eigenvalues of its monodromy matrix; the orbit is stable where all lie inside the unit circle
and loses stability where one leaves it: through +1 (fold / cyclic fold), through -1 (flip,
period doubling) or as a complex pair (Neimark–Sacker) (Guckenheimer & Holmes 1983, Sec. 3.5;
Seydel 2010, Sec. 7.4).
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import xarray as xr

from workbench._attributes import named, variable
from workbench._checks import positive_int
from workbench.analysis._window import EXPLICIT_METHODS, Window, measurement_window
from workbench.run import integrate as integrate_scene
from workbench.run import prepare
from workbench.scene import Scene, SceneSource, scene_from_toml
from workbench.solver import jacobian_for, state_scale, tangent_columns, tangent_problem

__all__ = ["floquet", "floquet_sweep", "jacobian_spectrum"]

#: |multiplier| beyond 1 by more than this counts as unstable
UNIT_CIRCLE_TOLERANCE = 1e-6


def _scene_of(run_or_scene) -> Scene:
    if isinstance(run_or_scene, xr.Dataset):
        if "scene" not in run_or_scene.attrs:
            raise ValueError(
                "the dataset has no 'scene' attribute: pass a run of workbench.simulate (or "
                "its scene)"
            )
        return scene_from_toml(run_or_scene.attrs["scene"])
    from workbench.scene import load_scene

    return load_scene(run_or_scene)


def _modes(prepared, t: np.ndarray) -> tuple[list[str], np.ndarray]:
    """Names of the modes of a run (contact per joint where the model outputs ``penetration``;
    else which event surfaces the state lies beyond) and each record's mode index."""
    model = prepared.model
    declared = model.variables(prepared.scene.effects)
    if "penetration" in declared:
        full = prepare(prepared.scene, variables=("penetration",))
        res = integrate_scene(full, t)
        res.raise_for_status()
        out = full.model.derive(full.problem, res.t, res.Y, res.AUX, ("penetration",))
        pen = np.asarray(out["penetration"])
        joints = list(model.coords(prepared.scene.effects)["joint"][0])
        contact = pen > 0.0
        names = [
            " ".join(f"{j}:{'contact' if c else 'free'}" for j, c in zip(joints, row, strict=True))
            for row in contact
        ]
    else:
        names = ["(no modes)"] * t.size
    kinds = sorted(set(names))
    return kinds, np.array([kinds.index(n) for n in names])


def jacobian_spectrum(
    run_or_scene: xr.Dataset | SceneSource,
    *,
    times: np.ndarray | None = None,
) -> xr.Dataset:
    """Eigenvalues of the model's Jacobian (its compiled analytic hook, or central differences
    of its compiled right-hand side) at the states of a run.

    Parameters
    ----------
    run_or_scene : Dataset or scene
        A run of :func:`workbench.simulate` (its scene is integrated again, bit for bit) or a
        scene.
    times : array_like, optional
        Times (s) at which to evaluate; default the run's record times.

    Returns
    -------
    xarray.Dataset
        ``eigenvalue_real`` (s-1) and ``eigenvalue_imag`` (rad s-1) over ``time`` and
        ``eigen`` (sorted by decreasing real part), ``mode`` per time (index into the
        ``modes`` coordinate: contact at each joint for the mechanisms), ``largest_real``
        (s-1) and its ``frequency`` (Hz, the imaginary part over 2 pi) per time; summaries
        per mode: ``mode_max_real`` (s-1), ``mode_median_real`` (s-1), ``mode_frequency``
        (Hz, at the largest real part), ``mode_fraction`` (of the records) and
        ``unstable_fraction`` (records with a positive real part).

    Examples
    --------
    >>> scene = {"model": {"name": "duffing"}, "run": {"cycles": 1},
    ...          "parameters": {"alpha": 1.0, "beta": 0.0, "gamma": 0.0, "delta": 0.2}}
    >>> r = jacobian_spectrum(scene)
    >>> [round(float(v), 6) for v in r.eigenvalue_real.isel(time=0)]   # -delta / 2 twice
    [-0.1, -0.1]
    """
    scene = _scene_of(run_or_scene)
    prepared = prepare(scene, variables=())
    t = prepared.times if times is None else np.asarray(times, dtype=float)
    res = integrate_scene(prepared, t)
    res.raise_for_status()
    pb = prepared.problem
    n, na = pb.y0.size, pb.aux0.size
    jac = jacobian_for(pb.hooks)
    Js = np.empty((t.size, n, n))
    Jas = np.empty((t.size, n, na))
    work = np.zeros(max(pb.work_size, 1))
    Y = np.ascontiguousarray(res.Y)
    codes = jac.jacobians_along(res.t, Y, res.AUX, pb.p, pb.ip, work, state_scale(pb), Js, Jas)
    if codes.any():
        bad = int(np.flatnonzero(codes)[0])
        raise ValueError(
            f"the model cannot be evaluated at t = {res.t[bad]:.9g} s: "
            f"{pb.failure(int(codes[bad]))}"
        )
    lam = np.linalg.eigvals(Js)
    order = np.argsort(-lam.real, axis=1)
    lam = np.take_along_axis(lam, order, axis=1)
    kinds, mode = _modes(prepared, res.t)
    top = lam[:, 0]
    per_mode = {
        "mode_max_real": [],
        "mode_median_real": [],
        "mode_frequency": [],
        "mode_fraction": [],
        "unstable_fraction": [],
    }
    for k in range(len(kinds)):
        sel = mode == k
        re = top.real[sel]
        i = int(np.argmax(re))
        per_mode["mode_max_real"].append(float(re[i]))
        per_mode["mode_median_real"].append(float(np.median(re)))
        per_mode["mode_frequency"].append(float(abs(top.imag[sel][i]) / (2 * np.pi)))
        per_mode["mode_fraction"].append(float(sel.mean()))
        per_mode["unstable_fraction"].append(float(np.mean(re > 0)))
    attrs = {
        "mode_max_real": ("s-1", "largest real part of an eigenvalue in the mode"),
        "mode_median_real": ("s-1", "median over the mode's records of the largest real part"),
        "mode_frequency": ("Hz", "frequency of the eigenvalue with the largest real part"),
        "mode_fraction": ("1", "fraction of the records in the mode"),
        "unstable_fraction": ("1", "fraction of the mode's records with a positive real part"),
    }
    data = {
        "eigenvalue_real": (
            ("time", "eigen"),
            lam.real,
            variable("real part of an eigenvalue of the Jacobian", "s-1"),
        ),
        "eigenvalue_imag": (
            ("time", "eigen"),
            lam.imag,
            variable("imaginary part of an eigenvalue of the Jacobian", "rad s-1"),
        ),
        "mode": ("time", mode, variable("mode index (see modes)")),
        "largest_real": (
            "time",
            top.real,
            variable("largest real part of the Jacobian's eigenvalues", "s-1"),
        ),
        "frequency": (
            "time",
            np.abs(top.imag) / (2 * np.pi),
            variable("frequency of the eigenvalue with the largest real part", "Hz"),
        ),
    }
    for key, values in per_mode.items():
        units, long_name = attrs[key]
        data[key] = ("modes", values, variable(long_name, units))
    return xr.Dataset(
        data,
        coords={
            "time": ("time", res.t, variable("time", "s")),
            "eigen": ("eigen", np.arange(n), variable("eigenvalue index")),
            "modes": ("modes", kinds, named("mode of the records")),
        },
        attrs={
            "method": "analytic Jacobian"
            if jac.HAS_ANALYTIC
            else "Jacobian by central differences of the rhs",
            "scene": scene.to_toml(),
        },
    )


def _monodromy(window: Window, y0: np.ndarray, aux0: np.ndarray, span: float, rtol: float):
    """State after ``span`` seconds from (y0, aux0) at the window's start, and the tangent map
    d y(t0 + span) / d y(t0) (state units), with saltation at events."""
    pb = window.problem
    n, na = pb.y0.size, pb.aux0.size
    s = state_scale(pb)
    V = np.zeros((n + na, n))
    V[:n] = np.diag(s)
    tp = tangent_problem(dataclasses.replace(pb, y0=y0, aux0=aux0), V, time_scale=span)
    res = window.solve(tp, np.array([pb.t0 + span]), rtol)
    y, V, _ = tangent_columns(res.Y[-1], n, na, n)
    return y.copy(), res.AUX[-1].copy(), V[:n] / s[None, :]


def floquet(
    scene: SceneSource,
    *,
    periods: int = 1,
    newton: bool = True,
    tolerance: float = 1e-10,
    max_iterations: int = 20,
    rtol: float | None = None,
) -> xr.Dataset:
    """Floquet multipliers of a periodic orbit of a forced model: the eigenvalues of the
    monodromy matrix over ``periods`` forcing periods from the state at the end of the scene's
    transient, refined first by Newton's method on the stroboscopic map (the orbit's state
    x with P^k(x) = x, ``k = periods``; the monodromy matrix is the map's Jacobian).

    Parameters
    ----------
    scene : Scene, path or mapping
        A forced model; ``run.transient_cycles`` bring the state near the orbit.
    periods : int
        The orbit's period in forcing periods (1 for period 1, 2 after a period doubling).
    newton : bool
        Refine the orbit's state (else the multipliers of the map at the transient's end).
    tolerance : float
        Newton stops when the scaled residual |P^k(x) - x| / s is below this.
    max_iterations : int
        Newton's iterations at most; when they run out, the multipliers are those at the last
        state (no error: ``residual`` and the attribute ``newton_iterations`` say how close
        and how many).
    rtol : float, optional
        Integration tolerance (default min(scene's rtol, 1e-10)).

    Returns
    -------
    xarray.Dataset
        ``multiplier_real`` and ``multiplier_imag`` (1) over ``multiplier`` (sorted by
        decreasing modulus), ``modulus``, ``orbit_state`` (the refined state, state units)
        over ``state``, ``residual`` (scaled), ``stable``, and ``loss`` (how the largest
        multiplier leaves the unit circle: "stable", "fold" (+1), "flip" (-1) or
        "neimark-sacker"); attribute ``tangent_method``, the method that integrated the
        monodromy matrix.

    Warns
    -----
    UserWarning
        Where the scene's method is implicit (``radau``, ``auto``, ``ark548``): it runs the
        transient, and the monodromy matrix is integrated with DOP853.

    Examples
    --------
    >>> r = floquet({"model": {"name": "duffing"}, "parameters": {"gamma": 0.2},
    ...              "initial": {"x": 1.0, "v": 0.0}, "run": {"transient_cycles": 100}})
    >>> str(r.loss.values), bool(r.stable)
    ('stable', True)
    """
    window = measurement_window(scene, cycles=1)
    if window.period is None:
        raise ValueError(f"model {window.prepared.scene.model!r} is not forced: no Floquet map")
    periods = positive_int("periods", periods)
    rtol = min(window.rtol, 1e-10) if rtol is None else float(rtol)
    if window.method not in EXPLICIT_METHODS:
        warnings.warn(
            f"floquet: the monodromy matrix is integrated with DOP853, not with "
            f"solver.method={window.method!r} (which ran the transient): the tangent system "
            "carries none of the model's implicit setup (its stiff states for ark548; radau and "
            "auto would difference the Jacobian over all its states); set solver.method = "
            "'dop853' to use one method throughout",
            stacklevel=2,
        )
    pb = window.problem
    s = state_scale(pb)
    span = periods * window.period
    x, aux = pb.y0.copy(), pb.aux0.copy()
    residual = np.inf
    iterations = 0
    while True:
        y1, aux1, M = _monodromy(window, x, aux, span, rtol)
        residual = float(np.linalg.norm((y1 - x) / s))
        if not newton or residual < tolerance or iterations >= max_iterations:
            break
        x = x - np.linalg.solve(M - np.eye(x.size), y1 - x)
        iterations += 1
    mu = np.linalg.eigvals(M)
    mu = mu[np.argsort(-np.abs(mu))]
    modulus = np.abs(mu)
    stable = bool(modulus[0] < 1 + UNIT_CIRCLE_TOLERANCE)
    if stable:
        loss = "stable"
    elif abs(mu[0].imag) > 1e-9 * modulus[0]:
        loss = "neimark-sacker"
    else:
        loss = "fold" if mu[0].real > 0 else "flip"
    names = [q.name for q in pb.states]
    return xr.Dataset(
        {
            "multiplier_real": ("multiplier", mu.real, variable("real part")),
            "multiplier_imag": (
                "multiplier",
                mu.imag,
                variable("imaginary part"),
            ),
            "modulus": ("multiplier", modulus, variable("|multiplier|")),
            "orbit_state": (
                "state",
                x,
                named(
                    "state on the orbit at the strobe time",
                    comment="each state in its own units: the coordinate state_units",
                ),
            ),
            "residual": (
                (),
                residual,
                variable("scaled |P^k(x) - x| of the orbit state"),
            ),
            "stable": ((), stable, variable("all multipliers inside the unit circle")),
            "loss": ((), loss, named("how the largest multiplier leaves the unit circle")),
        },
        coords={
            "multiplier": ("multiplier", np.arange(mu.size), variable("multiplier index")),
            "state": ("state", names, named("state variable")),
            "state_units": ("state", [q.units for q in pb.states], named("units of the state")),
        },
        attrs={
            "periods": periods,
            "newton_iterations": iterations,
            "rtol": rtol,
            "tangent_method": window.method if window.method in EXPLICIT_METHODS else "dop853",
            "strobe_time": pb.t0,
            "method": "monodromy matrix of the variational equations with saltation, Newton "
            "on the stroboscopic map",
        },
    )


def floquet_sweep(
    scene: SceneSource,
    parameter: str,
    values,
    *,
    periods: int = 1,
    rtol: float | None = None,
) -> xr.Dataset:
    """Floquet multipliers of a periodic orbit continued over a parameter: the orbit at each
    value starts Newton's method from the orbit of the previous value (natural-parameter
    continuation; Seydel 2010, Sec. 4.1), so that a bifurcation diagram can mark where the orbit
    loses stability and how.

    Parameters
    ----------
    scene : Scene, path or mapping
        Its transient brings the first value's state near the orbit.
    parameter : str
        A model parameter (SI units).
    values : array_like
        Its values, in the order of the continuation.
    periods : int
        The orbit's period in forcing periods.
    rtol : float, optional
        Integration tolerance of every value's :func:`floquet` (default min(scene's rtol,
        1e-10)).

    Returns
    -------
    xarray.Dataset
        :func:`floquet`'s variables over dim ``parameter``; attributes ``first_loss_value``
        (the parameter value where the largest modulus first reaches 1, interpolated linearly
        between the two values around it; NaN if none) and ``first_loss_kind``.
    """
    from workbench.scene import load_scene

    base = load_scene(scene)
    values = np.asarray(values, dtype=float)
    out = []
    current = base
    for v in values:
        params = {**base.parameters, parameter: float(v)}
        current = current.replace(parameters=params)
        r = floquet(current, periods=periods, rtol=rtol)
        out.append(r)
        orbit = zip(r.state.values, r.orbit_state.values, strict=True)
        initial = {str(name): float(x) for name, x in orbit}
        run = dict(current.run)
        run["transient_cycles"] = 0
        current = current.replace(initial=initial, run=run)
    ds = xr.concat(out, dim=parameter, coords="minimal", compat="override")
    attrs = {}
    if parameter in base.resolved_parameters:
        from workbench.models import get_model

        p = get_model(base.model).parameter(parameter)
        attrs = variable(p.long_name, p.units)
    ds = ds.assign_coords({parameter: (parameter, values, attrs)})
    top = ds.modulus.isel(multiplier=0).values
    first = np.flatnonzero(top >= 1 + UNIT_CIRCLE_TOLERANCE)
    ds.attrs["first_loss_value"] = np.nan
    ds.attrs["first_loss_kind"] = "none"
    if first.size and first[0] > 0:
        i = int(first[0])
        a, b = top[i - 1], top[i]
        ds.attrs["first_loss_value"] = float(
            values[i - 1] + (1.0 - a) / (b - a) * (values[i] - values[i - 1])
        )
        ds.attrs["first_loss_kind"] = str(ds.loss.values[i])
    return ds
