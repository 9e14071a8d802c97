"""Run a scene in the workbench and in exudyn and compare them (``workbench.verify``).

Ideal joints: the motion is prescribed, so the driving torques and the slider kinematics must
agree record by record (the only differences are exudyn's time-discretisation error, second
order in the step, and the start-up transient of generalised-alpha's Lagrange multipliers,
Arnold & Bruls 2007, which decays within a few dozen steps).

Clearance joints: the motion is chaotic (Chen et al. 2019, Sec. 5), so two correct solutions
part after a few impacts. Compared are (1) the first impact at each joint, before any divergence
(time of first contact and peak normal force), and (2) statistics that do not depend on the
phase of the chaos: the fraction of time in contact, the mean eccentricity, the 95th percentile
and the peak of the contact force and the RMS driving torque, each over the whole horizon. Exudyn
runs at several fixed steps (step refinement); its spread across steps is the scale against
which the workbench's difference is judged.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench.models import get_model
from workbench.run import simulate
from workbench.scene import SceneError, SceneSource, load_scene
from workbench.verification._exudyn import run_exudyn
from workbench.verification._mechanisms import check_scene

_SERIES = (
    "torque",
    "slider_position",
    "slider_velocity",
    "slider_acceleration",
    "clearance_x",
    "clearance_y",
    "contact_force",
)

# statistic name -> (units, long name)
STATISTICS = {
    "contact_fraction": ("1", "fraction of the horizon in contact"),
    "mean_eccentricity": ("m", "mean eccentricity of the journal"),
    "force_p95": ("N", "95th percentile of the contact force while in contact"),
    "peak_force": ("N", "largest contact force"),
}


def _first_impacts(ds: xr.Dataset) -> tuple[np.ndarray, np.ndarray]:
    """Time (s) of the first record in contact and peak force (N) of that contact, per joint."""
    t = ds.time.values
    times, peaks = [], []
    for j in ds.joint.values:
        f = ds.contact_force.sel(joint=j).values
        on = np.flatnonzero(f > 0.0)
        if not on.size:
            times.append(np.nan)
            peaks.append(np.nan)
            continue
        i0 = on[0]
        off = np.flatnonzero(f[i0:] <= 0.0)
        i1 = i0 + (off[0] if off.size else f.size - i0)
        times.append(t[i0])
        peaks.append(f[i0:i1].max())
    return np.array(times), np.array(peaks)


def _statistics(ds: xr.Dataset) -> dict[str, np.ndarray]:
    f = ds.contact_force.values  # (time, joint)
    e = np.hypot(ds.clearance_x.values, ds.clearance_y.values)
    contact = f > 0.0
    p95 = [
        np.percentile(f[contact[:, k], k], 95) if contact[:, k].any() else 0.0
        for k in range(f.shape[1])
    ]
    return {
        "contact_fraction": contact.mean(axis=0),
        "mean_eccentricity": e.mean(axis=0),
        "force_p95": np.array(p95),
        "peak_force": f.max(axis=0),
    }


def verify(
    scene: SceneSource,
    *,
    horizon: float | None = None,
    steps: Sequence[float] = (4e-6, 2e-6, 1e-6),
    record_dt: float | None = None,
    rtol: float = 1e-10,
    spectral_radius: float = 0.6,
    on_run: Callable[[float | None, str, float], None] | None = None,
) -> xr.Dataset:
    """Compare a mechanism scene between the workbench and exudyn.

    Parameters
    ----------
    scene : Scene or path
        A scene of the ``ninebar`` or ``slider_crank`` model or of a declared mechanism (a
        ``[mechanism]`` table), with friction "none" or "coulomb" (see
        :mod:`workbench.verification._exudyn` for what each side models).
    horizon : float, optional
        Simulated time from t = 0, s (default: one crank period).
    steps : sequence of float
        Exudyn's fixed steps, s, coarse to fine (step refinement).
    record_dt : float, optional
        Record interval of both sides, s, a whole multiple of every step (default: the
        coarsest step with clearances, which resolves the contact peaks; 1 ms for ideal joints).
    rtol : float
        The workbench's tolerance (rtol = atol, scaled as in the scene).
    spectral_radius : float
        Numerical damping of exudyn's generalised-alpha (see :func:`run_exudyn`).
    on_run : callable, optional
        Called as each run ends, ``on_run(step, label, wall_time)``: exudyn's step (s; None
        for the workbench's run), the run's label and its wall time (s); e.g. progress.

    Returns
    -------
    xarray.Dataset
        Dim ``run`` ("workbench", then "exudyn h=..." per step) with coordinates ``engine`` and
        ``step`` (s; NaN for the workbench), dim ``time``; the compared series of every run
        (the slider's only where the model records a slider);
        ``wall_time`` (s) per run; ``max_relative_error`` per run and series (largest difference
        from the workbench over the horizon divided by the workbench's largest magnitude); with
        clearances ``first_impact_time`` (s) and ``first_impact_force`` (N) per run and joint and
        the statistics of :data:`STATISTICS` per run and joint.

    Examples
    --------
    >>> from workbench.verification import verify                               # doctest: +SKIP
    >>> ds = verify("studies/ninebar.toml", horizon=0.02, steps=(2e-6,))  # doctest: +SKIP
    >>> ds.first_impact_time.sel(joint="A").values                         # doctest: +SKIP
    array([0.011782, 0.011782])
    """
    scene = load_scene(scene)
    if scene.sweep:
        raise SceneError(
            "sweep",
            f"the scene sweeps {list(scene.sweep)!r}; verify runs one scene: drop the sweep "
            "(scene.replace(sweep={}))",
        )
    check_scene(scene)  # before the workbench's own (possibly long) run
    steps = sorted((float(h) for h in steps), reverse=True)
    if not steps or min(steps) <= 0:
        raise ValueError(f"steps must be positive time steps in s; got {steps!r}")
    joints = tuple(scene.effects["clearance"])
    params = scene.resolved_parameters
    period = 2.0 * np.pi / params["omega"]
    horizon = float(horizon or period)
    record_dt = float(record_dt or (steps[0] if joints else 1e-3))
    for h in steps:
        ratio = record_dt / h
        if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-6 * ratio:
            raise ValueError(
                f"record_dt = {record_dt!r} s must be a whole multiple of every step; step "
                f"{h!r} s gives {ratio:g} (choose steps that divide record_dt)"
            )
    recorded = {q.name for q in get_model(scene.model).outputs(scene.effects)}
    variables = [v for v in _SERIES if v in recorded]
    ours_scene = scene.replace(
        run={"duration": horizon},
        record={"dt": record_dt, "variables": variables},
        solver={"method": "dop853", "rtol": rtol, "atol": rtol},
    )
    ours = simulate(ours_scene)
    runs = [ours[variables].assign_attrs(wall_time=ours.attrs["solver_wall_time"])]
    if on_run is not None:
        on_run(None, f"workbench (dop853, rtol {rtol:g})", ours.attrs["solver_wall_time"])
    for h in steps:
        ex = run_exudyn(
            scene, t_end=horizon, step=h, record_dt=record_dt, spectral_radius=spectral_radius
        )
        n = min(ex.sizes["time"], ours.sizes["time"])
        if not np.allclose(ex.time.values[:n], ours.time.values[:n], rtol=0, atol=1e-3 * h):
            raise RuntimeError("exudyn's records do not fall on the workbench's record times")
        ex = ex.isel(time=slice(0, n)).assign_coords(time=ours.time[:n])
        runs.append(ex[variables].assign_attrs(wall_time=ex.attrs["wall_time"]))
        if on_run is not None:
            on_run(h, f"exudyn h={h:g} ({horizon / h:.0f} steps)", ex.attrs["wall_time"])
    labels = ["workbench"] + [f"exudyn h={h:g}" for h in steps]
    ds = xr.concat(runs, dim="run", join="inner", combine_attrs="drop")
    ds = ds.assign_coords(
        run=("run", labels, variable("run")),
        engine=("run", ["workbench"] + ["exudyn"] * len(steps), {"units": "1"}),
        step=("run", [np.nan, *steps], variable("exudyn's fixed step", "s")),
    )
    for v in variables:
        ds[v].attrs = dict(ours[v].attrs)
    ds["wall_time"] = (
        "run",
        [r.attrs["wall_time"] for r in runs],
        variable("wall time", "s"),
    )
    ref = ds.sel(run="workbench")
    errors = []
    for v in variables:
        diff = abs(ds[v] - ref[v]).max([d for d in ds[v].dims if d != "run"])
        errors.append(diff / float(abs(ref[v]).max()))
    ds["max_relative_error"] = xr.concat(
        errors, dim=xr.DataArray(variables, dims="series")
    ).assign_attrs(variable("largest difference from the workbench over its largest magnitude"))
    if joints:
        first = [_first_impacts(ds.sel(run=r)) for r in labels]
        ds["first_impact_time"] = (
            ("run", "joint"),
            np.array([f[0] for f in first]),
            variable("time of the first contact", "s"),
        )
        ds["first_impact_force"] = (
            ("run", "joint"),
            np.array([f[1] for f in first]),
            variable("peak normal force of the first contact", "N"),
        )
        stats = [_statistics(ds.sel(run=r)) for r in labels]
        for name, (units, long_name) in STATISTICS.items():
            ds[name] = (
                ("run", "joint"),
                np.array([s[name] for s in stats]),
                variable(long_name, units),
            )
    ds.attrs.update(
        title="workbench against exudyn",
        scene=scene.to_toml(),
        horizon=horizon,
        record_dt=record_dt,
        workbench_rtol=rtol,
        exudyn_spectral_radius=spectral_radius,
    )
    return ds
