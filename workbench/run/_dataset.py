"""A run's records become a labelled dataset: derived outputs, units, provenance, statistics."""

from __future__ import annotations

import dataclasses
import datetime
import platform
from functools import cache, lru_cache
from importlib.metadata import PackageNotFoundError, version

import numpy as np
import xarray as xr

from workbench._attributes import flags, variable
from workbench._processor import processor_attrs
from workbench._sources import code_digest
from workbench._version import FORMAT_VERSION, __version__
from workbench.models import get_model
from workbench.run._ensemble import REALISATION_ATTRS
from workbench.run._parameters import PARAMETERS_ATTR, parameter_coords
from workbench.run._prepare import Prepared
from workbench.scene import Scene
from workbench.solver import TEMPLATE_MODULES, RunResult, SolverError, Status

__all__ = [
    "TIME_ATTRS",
    "derive",
    "end_state_attrs",
    "provenance",
    "references",
    "run_status",
    "status_attrs",
    "to_dataset",
]

_PACKAGES = ("workbench", "numpy", "scipy", "numba", "xarray", "netCDF4", "dask")
TIME_ATTRS = variable("time", "s", standard_name="time")


def derive(prepared: Prepared, result: RunResult) -> tuple[dict[str, np.ndarray], RunResult]:
    """The model's derived outputs at the run's records, and the result they leave.

    Outputs are computed over the records that hold the solution and NaN after them. A model
    that finds a record outside its domain (it raises :class:`SolverError`) ends the run there:
    the returned result then has :attr:`Status.MODEL_FAILURE`, the model's message, and only
    the records before that one.
    """
    try:
        return _derive_valid(prepared, result), result
    except SolverError as exc:
        n = int(np.searchsorted(result.t, exc.time, side="left"))
        Y, AUX = result.Y.copy(), result.AUX.copy()
        Y[n:], AUX[n:] = np.nan, np.nan
        failed = dataclasses.replace(
            result,
            Y=Y,
            AUX=AUX,
            status=exc.status,
            message=str(exc),
            recorded=min(n, result.recorded),
            time=exc.time,
            state=exc.state,
            model_code=exc.model_code,
        )
        return _derive_valid(prepared, failed), failed


def _derive_valid(prepared: Prepared, result: RunResult) -> dict[str, np.ndarray]:
    """Derived outputs over the first ``result.recorded`` records, NaN-padded to all records."""
    p, n, size = prepared, result.recorded, result.t.size
    if n == size:
        return p.model.derive(p.problem, result.t, result.Y, result.AUX, p.variables)
    outputs = {q.name: q for q in p.model.outputs(p.scene.effects) if q.name in p.variables}
    sizes = {d: len(v) for d, (v, _) in p.model.coords(p.scene.effects).items()}
    full = {
        name: np.full((size,) + tuple(sizes[d] for d in q.dims), np.nan)
        for name, q in outputs.items()
    }
    if n > 0:
        valid = p.model.derive(p.problem, result.t[:n], result.Y[:n], result.AUX[:n], p.variables)
        for name, values in valid.items():
            full[name][:n] = values
    return full


def to_dataset(prepared: Prepared, result: RunResult, derived: dict[str, np.ndarray]) -> xr.Dataset:
    """Labelled dataset of a run: only the requested variables, with units everywhere.

    Every resolved parameter of the model is a scalar coordinate with its units
    (:func:`workbench.run.parameter_coords`; their names in the attribute ``model_parameters``),
    and so is ``realisation`` when the scene asks for one. Global attributes:
    :func:`provenance`, the solver's statistics (``solver_*``), the model, ``run_status`` (a
    :class:`Status` label) and ``run_message`` (empty when ok), the forcing period, the
    attributes of the record times and the state the run ended in (:func:`end_state_attrs`).
    """
    scene, model = prepared.scene, prepared.model
    declared = model.variables(scene.effects)
    state_index = {q.name: i for i, q in enumerate(prepared.problem.states)}
    coords = {"time": ("time", result.t, dict(TIME_ATTRS))}
    for dim, (values, attrs) in model.coords(scene.effects).items():
        coords[dim] = (dim, list(values), dict(attrs))
    data_vars = {}
    for name in prepared.variables:
        q = declared[name]
        values = result.Y[:, state_index[name]] if name in state_index else derived[name]
        attrs = variable(q.long_name, q.units)
        if q.rate in prepared.variables:
            attrs["rate_variable"] = q.rate
        data_vars[name] = (("time",) + q.dims, values, attrs)
    params = parameter_coords(model, prepared.parameters, taken=[*coords, *declared])
    coords.update(params)
    if "realisation" in scene.run:
        coords["realisation"] = ((), np.int64(scene.run["realisation"]), dict(REALISATION_ATTRS))
    ds = xr.Dataset(data_vars, coords=coords)
    ds.attrs[PARAMETERS_ATTR] = " ".join(params)
    ds.attrs.update(provenance(scene))
    ds.attrs.update({f"solver_{k}": v for k, v in result.stats.items()})
    ds.attrs["run_status"] = result.status.label
    ds.attrs["run_message"] = result.message
    ds.attrs["model"] = scene.model
    if prepared.period is not None:
        ds.attrs["forcing_period"] = float(prepared.period)
        ds.attrs["forcing_period_units"] = "s"
    ds.attrs.update(prepared.record_attrs)
    ds.attrs.update(end_state_attrs(prepared, result))
    return ds


def end_state_attrs(prepared: Prepared, result: RunResult) -> dict:
    """The state a run ended in, as attributes, so that a measurement of the run continues from
    it instead of integrating the run again: ``end_time`` (s), ``end_state`` (every state of
    the problem, in its order and its units, whether recorded or not), ``end_state_names``
    (their names, space-separated) and ``end_discrete_state`` (the discrete state, e.g. a
    contact's held onset velocity; absent for a model without one). The end is the last
    record that holds the solution (the run's end for a completed run); none for a run
    without one."""
    n = result.recorded
    if n < 1:
        return {}
    out = {
        "end_time": float(result.t[n - 1]),
        "end_state": np.asarray(result.Y[n - 1], dtype=np.float64).copy(),
        "end_state_names": " ".join(q.name for q in prepared.problem.states),
    }
    if result.AUX.shape[1] > 0:
        out["end_discrete_state"] = np.asarray(result.AUX[n - 1], dtype=np.float64).copy()
    return out


def status_attrs(long_name: str, extra: dict[int, str] | None = None) -> dict:
    """Attributes of an int8 variable of :class:`Status` flags (CF ``flag_values`` and
    ``flag_meanings``), with ``extra`` flags (value -> meaning) after the statuses."""
    return flags(long_name, {int(s): s.label for s in Status} | (extra or {}))


def run_status(ds: xr.Dataset) -> Status:
    """The :class:`Status` a dataset of :func:`workbench.simulate` records."""
    return Status.from_label(ds.attrs["run_status"])


def provenance(scene: Scene, *, by: str = "workbench.simulate") -> dict:
    """Global attributes every stored dataset carries (CF conventions, scene, versions).

    ``by`` names the function that created the dataset (in ``history``); ``references`` cites
    the model's source (:attr:`workbench.models.Model.reference`) and this package.
    """
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    versions, source = _versions()
    return {
        "Conventions": "CF-1.11",
        "title": scene.title or f"workbench run of model {scene.model}",
        "history": f"{now} created by {by}",
        "source": source,
        "references": references(scene.model),
        "scene": scene.to_toml(),
        "package_versions": versions,
        "code_digest": results_digest(scene.model),
        **processor_attrs(),
        "format_version": np.int32(FORMAT_VERSION),
    }


@cache
def references(model: str) -> str:
    """The global attribute ``references`` of a dataset of ``model``: the model's source, then
    this package (its version and distribution name)."""
    package = f"computed with workbench {__version__} (Python distribution clearance-workbench)"
    cited = get_model(model).reference
    return f"{cited}; {package}" if cited else package


@cache
def results_digest(model: str, *modules: str) -> str:
    """16-hex digest of the code that computes a run of ``model``: the run layer, the model's
    module, the compiled kernels' templates and everything they import, and ``modules`` (e.g.
    the campaign's block task), with the versions of Python, numba and NumPy
    (:func:`workbench._sources.code_digest`; docstrings and comments do not count). Equal
    digests and the same compile target (:func:`workbench._processor.processor_attrs`): the
    same scene gives the same numbers; on another target they agree within their errors."""
    model_module = type(get_model(model)).__module__
    return code_digest("workbench.run", model_module, *TEMPLATE_MODULES, *modules)


@lru_cache(maxsize=1)
def _versions() -> tuple[str, str]:
    """Package versions and the source line; read once per process (metadata look-ups cost
    milliseconds, more than a short run)."""
    found = []
    for pkg in _PACKAGES:
        if pkg == "workbench":
            found.append(f"workbench={__version__}")
            continue
        try:
            found.append(f"{pkg}={version(pkg)}")
        except PackageNotFoundError:
            found.append(f"{pkg}=unknown")
    # the package's own version from its code: an editable install's metadata keeps the
    # version it was installed with
    source = (
        f"workbench {__version__} ({platform.python_implementation()} {platform.python_version()})"
    )
    return "; ".join(found), source
