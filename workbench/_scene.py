"""Scenes: the declarative description of a run (TOML), validated and frozen.

A scene has the tables ``[model]``, ``[effects]``, ``[parameters]``, ``[initial]``, ``[solver]``,
``[run]``, ``[record]`` and ``[sweep]`` (and optional top-level ``title`` and ``description``).
Every error names the offending key as a dotted path, shows the value and says what is allowed.

>>> from workbench import load_scene
>>> s = load_scene({"model": {"name": "duffing"}, "parameters": {"gamma": 0.3}})
>>> s.parameters["gamma"], s.solver["method"]
(0.3, 'dop853')
>>> load_scene(s.to_toml()) == s
True
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
import tomli_w

from workbench._ensemble import MAX_PERTURBATION
from workbench._errors import SceneError
from workbench.models import available_models, get_model

__all__ = ["Scene", "load_scene", "COMPILED_METHODS", "SCIPY_METHODS"]

COMPILED_METHODS = ("dop853", "dopri5", "ark548")
SCIPY_METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
_TABLES = (
    "title",
    "description",
    "model",
    "effects",
    "parameters",
    "initial",
    "solver",
    "run",
    "record",
    "sweep",
)
_ENSEMBLE = ("realisation", "perturbation")  # [run] keys of an ensemble (workbench._ensemble)
RUN_SWEEP_KEYS = ("realisation",)  # [run] keys a [sweep] may list (see workbench._ensemble)
_SOLVER_DEFAULTS = {
    "method": "dop853",
    "rtol": 1e-8,
    "atol": 1e-10,
    "max_step": math.inf,
    "max_steps": 50_000_000,
    "check": False,
}


def _frozen(d: Mapping) -> Mapping:
    return MappingProxyType(dict(d))


@dataclass(frozen=True, eq=False)
class Scene:
    """A validated scene. Build it with :func:`load_scene`; it is immutable.

    Attributes
    ----------
    model : str
        Registered model name.
    effects : Mapping
        Every effect of the model, defaults filled in.
    parameters : Mapping[str, float]
        The parameters the scene overrides (SI units); :attr:`resolved_parameters` adds defaults.
    initial : Mapping[str, float]
        Initial-state overrides (state units).
    solver, run, record : Mapping
        Solver settings, run length, what and how often to record (defaults filled in).
    sweep : Mapping[str, tuple[float, ...]]
        Parameter name -> the values of that campaign dimension (empty for a single run).
    """

    model: str
    effects: Mapping[str, Any]
    parameters: Mapping[str, float]
    initial: Mapping[str, float]
    solver: Mapping[str, Any]
    run: Mapping[str, Any]
    record: Mapping[str, Any]
    sweep: Mapping[str, tuple[float, ...]] = field(default_factory=lambda: _frozen({}))
    title: str = ""
    description: str = ""

    # -- derived views --------------------------------------------------------------------------
    @property
    def resolved_parameters(self) -> dict[str, float]:
        """Model defaults overridden by this scene's parameters."""
        params = get_model(self.model).default_parameters()
        params.update(self.parameters)
        return params

    @property
    def variables(self) -> tuple[str, ...]:
        """The variables a run of this scene computes and stores."""
        return tuple(self.record["variables"])

    def to_dict(self) -> dict[str, Any]:
        """The scene as plain TOML-ready data (explicit, defaults included)."""
        d: dict[str, Any] = {}
        if self.title:
            d["title"] = self.title
        if self.description:
            d["description"] = self.description
        d["model"] = {"name": self.model}
        for key in ("effects", "parameters", "initial", "solver", "run", "record"):
            table = {
                k: (list(v) if isinstance(v, tuple) else v) for k, v in getattr(self, key).items()
            }
            if key == "solver" and math.isinf(table.get("max_step", 0.0)):
                table.pop("max_step")
            if table:
                d[key] = table
        if self.sweep:
            d["sweep"] = {k: list(v) for k, v in self.sweep.items()}
        return d

    def to_toml(self) -> str:
        """TOML text that :func:`load_scene` reads back to an equal scene."""
        return tomli_w.dumps(self.to_dict())

    def replace(self, **tables: Mapping) -> Scene:
        """A new validated scene with whole tables replaced, e.g. ``replace(sweep={})``."""
        d = self.to_dict()
        for k, v in tables.items():
            if k not in _TABLES:
                raise SceneError(k, f"unknown table; allowed: {', '.join(_TABLES)}")
            d[k] = dict(v) if isinstance(v, Mapping) else v
        return load_scene(d)

    def with_parameters(self, **values: float) -> Scene:
        """A single-run scene (no sweep) with some parameters changed: one point of a campaign
        grid. A swept ``[run]`` key (``realisation``) goes to ``[run]``."""
        run = dict(self.run)
        run.update({k: int(values.pop(k)) for k in list(values) if k in RUN_SWEEP_KEYS})
        params = dict(self.parameters)
        params.update({k: float(v) for k, v in values.items()})
        return self.replace(parameters=params, run=run, sweep={})

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Scene) and self.to_dict() == other.to_dict()

    def __hash__(self) -> int:
        return hash(self.to_toml())


# -- loading and validation ----------------------------------------------------------------------
def load_scene(source: str | Path | Mapping[str, Any]) -> Scene:
    """Read and validate a scene.

    Parameters
    ----------
    source : str, Path or Mapping
        A TOML file path, TOML text (a string containing a newline or ``=``), or a mapping with
        the TOML structure.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        Naming the offending key (dotted path), its value and what is allowed.
    """
    if isinstance(source, Mapping):
        data = dict(source)
    else:
        text, where = _read_text(source)
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise SceneError("", f"{where} is not valid TOML: {exc}") from None
    return _validate(data)


def _read_text(source: str | Path) -> tuple[str, str]:
    if isinstance(source, str) and ("\n" in source or "=" in source):
        return source, "scene text"
    path = Path(source)
    if not path.is_file():
        raise SceneError("", f"scene file {str(path)!r} does not exist")
    return path.read_text(), repr(str(path))


def _table(data: Mapping, key: str) -> dict:
    value = data.get(key, {})
    if not isinstance(value, Mapping):
        raise SceneError(key, f"must be a table, got {value!r}")
    return dict(value)


def _number(key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise SceneError(key, f"must be a number, got {value!r}")
    return float(value)


def _integer(key: str, value: Any, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise SceneError(key, f"must be an integer >= {minimum}, got {value!r}")
    if value < minimum:
        raise SceneError(key, f"must be an integer >= {minimum}, got {value!r}")
    return int(value)


def _positive(key: str, value: Any, *, allow_inf: bool = False) -> float:
    x = _number(key, value)
    if not (x > 0) or (math.isinf(x) and not allow_inf) or math.isnan(x):
        raise SceneError(
            key, f"must be a positive{' ' if allow_inf else ' finite '}number, got {value!r}"
        )
    return x


def _unknown(table: str, given: Mapping, allowed) -> None:
    for k in given:
        if k not in allowed:
            names = ", ".join(sorted(allowed)) or "(none)"
            raise SceneError(f"{table}.{k}" if table else k, f"unknown key; allowed: {names}")


def _validate(data: Mapping[str, Any]) -> Scene:
    _unknown("", data, _TABLES)
    for key in ("title", "description"):
        if key in data and not isinstance(data[key], str):
            raise SceneError(key, f"must be a string, got {data[key]!r}")
    model_t = _table(data, "model")
    _unknown("model", model_t, ("name",))
    name = model_t.get("name")
    if name is None:
        raise SceneError(
            "model.name", "is required; available models: " + ", ".join(available_models())
        )
    if name not in available_models():
        raise SceneError(
            "model.name", f"unknown model {name!r}; available: {', '.join(available_models())}"
        )
    model = get_model(name)

    effects = _validate_effects(model, _table(data, "effects"))
    parameters = _validate_parameters(model, _table(data, "parameters"), "parameters")
    resolved = model.default_parameters()
    resolved.update(parameters)
    model.validate(resolved, effects)

    states = {q.name for q in model.states(effects)}
    initial_t = _table(data, "initial")
    _unknown("initial", initial_t, states)
    initial = {k: _number(f"initial.{k}", v) for k, v in initial_t.items()}

    solver = _validate_solver(_table(data, "solver"))
    period = model.forcing_period(resolved)
    run_t = _table(data, "run")
    ensemble = _validate_ensemble(run_t)  # takes its keys out of run_t
    run = _validate_run(run_t, period is not None) | ensemble
    record = _validate_record(_table(data, "record"), model, effects, period is not None, run)
    sweep = _validate_sweep(model, _table(data, "sweep"), effects)
    return Scene(
        model=name,
        effects=_frozen(effects),
        parameters=_frozen(parameters),
        initial=_frozen(initial),
        solver=_frozen(solver),
        run=_frozen(run),
        record=_frozen(record),
        sweep=_frozen(sweep),
        title=data.get("title", ""),
        description=data.get("description", ""),
    )


def _validate_effects(model, given: dict) -> dict:
    declared = {e.name: e for e in model.effects}
    _unknown("effects", given, declared)
    effects = model.default_effects()
    for k, v in given.items():
        e = declared[k]
        key = f"effects.{k}"
        allowed = ", ".join(repr(a) for a in e.allowed)
        if e.kind == "choice":
            if v not in e.allowed:
                raise SceneError(key, f"got {v!r}; allowed: {allowed}")
        elif e.kind == "subset":
            if not isinstance(v, list | tuple) or any(x not in e.allowed for x in v):
                raise SceneError(
                    key, f"must be a list of distinct values among {allowed}, got {v!r}"
                )
            if len(set(v)) != len(v):
                raise SceneError(key, f"lists a value twice: {v!r}")
            v = tuple(x for x in e.allowed if x in v)  # canonical order
        elif e.kind == "bool":
            if not isinstance(v, bool):
                raise SceneError(key, f"must be true or false, got {v!r}")
        effects[k] = v
    return {k: (tuple(v) if isinstance(v, list) else v) for k, v in effects.items()}


def _validate_parameters(model, given: dict, table: str) -> dict[str, float]:
    declared = {p.name: p for p in model.parameters}
    _unknown(table, given, declared)
    out = {}
    for k, v in given.items():
        x = _number(f"{table}.{k}", v)
        problem = declared[k].check(x)
        if problem:
            raise SceneError(f"{table}.{k}", f"got {v!r}; {problem}")
        out[k] = x
    return out


def _validate_solver(given: dict) -> dict:
    _unknown("solver", given, _SOLVER_DEFAULTS)
    s = dict(_SOLVER_DEFAULTS)
    s.update(given)
    method = s["method"]
    allowed = list(COMPILED_METHODS) + [f"scipy:{m}" for m in SCIPY_METHODS]
    if not isinstance(method, str) or method not in allowed:
        raise SceneError("solver.method", f"got {method!r}; allowed: {', '.join(allowed)}")
    s["rtol"] = _positive("solver.rtol", s["rtol"])
    if not 1e-14 <= s["rtol"] < 1:
        raise SceneError("solver.rtol", f"got {s['rtol']!r}; must lie in [1e-14, 1)")
    s["atol"] = _positive("solver.atol", s["atol"])
    s["max_step"] = _positive("solver.max_step", s["max_step"], allow_inf=True)
    s["max_steps"] = _integer("solver.max_steps", s["max_steps"], 1)
    if not isinstance(s["check"], bool):
        raise SceneError(
            "solver.check",
            f"got {s['check']!r}; allowed: true or false (estimate the run's own "
            "error by a second run 100x tighter over the first period)",
        )
    return s


def _validate_run(given: dict, forced: bool) -> dict:
    if forced:
        _unknown("run", given, ("cycles", "transient_cycles", "duration", "transient", *_ENSEMBLE))
        if "cycles" in given or "transient_cycles" in given or not given:
            if "duration" in given or "transient" in given:
                raise SceneError(
                    "run", "give either cycles/transient_cycles or duration/transient, not both"
                )
            return {
                "cycles": _integer("run.cycles", given.get("cycles", 10), 1),
                "transient_cycles": _integer(
                    "run.transient_cycles", given.get("transient_cycles", 0), 0
                ),
            }
    else:
        for k in ("cycles", "transient_cycles"):
            if k in given:
                raise SceneError(
                    f"run.{k}", "this model has no forcing period; use run.duration (s) instead"
                )
        _unknown("run", given, ("duration", "transient", *_ENSEMBLE))
    if "duration" not in given:
        raise SceneError("run.duration", "is required (simulated time to record, s)")
    transient = _number("run.transient", given.get("transient", 0.0))
    if transient < 0 or math.isinf(transient):
        raise SceneError("run.transient", f"must be a finite number >= 0 s, got {transient!r}")
    return {"duration": _positive("run.duration", given["duration"]), "transient": transient}


def _validate_record(given: dict, model, effects, forced: bool, run: dict) -> dict:
    _unknown("record", given, ("samples_per_period", "dt", "variables"))
    rec: dict[str, Any] = {}
    if "samples_per_period" in given and "dt" in given:
        raise SceneError("record", "give either samples_per_period or dt, not both")
    if "samples_per_period" in given:
        if not forced:
            raise SceneError(
                "record.samples_per_period", "this model has no forcing period; use record.dt (s)"
            )
        rec["samples_per_period"] = _integer(
            "record.samples_per_period", given["samples_per_period"], 1
        )
    elif "dt" in given:
        rec["dt"] = _positive("record.dt", given["dt"])
    elif forced and "cycles" in run:
        rec["samples_per_period"] = 100
    else:
        rec["dt"] = run["duration"] / 1000.0
    available = model.variables(effects)
    variables = given.get("variables", list(available))
    if not isinstance(variables, list | tuple) or not variables:
        raise SceneError(
            "record.variables", f"must be a non-empty list of names, got {variables!r}"
        )
    for v in variables:
        if v not in available:
            raise SceneError(
                "record.variables", f"unknown variable {v!r}; available: {', '.join(available)}"
            )
    if len(set(variables)) != len(variables):
        raise SceneError("record.variables", f"lists a variable twice: {variables!r}")
    rec["variables"] = tuple(variables)
    return rec


def _validate_ensemble(run: dict) -> dict:
    """Take the ensemble keys ``realisation`` and ``perturbation`` out of the ``[run]`` table
    ``run`` and validate them (see :mod:`workbench._ensemble`); returns those given."""
    out: dict[str, Any] = {}
    if "realisation" in run:
        out["realisation"] = _integer("run.realisation", run.pop("realisation"), 0)
    if "perturbation" in run:
        size = run.pop("perturbation")
        x = _number("run.perturbation", size)
        if not 0 < x <= MAX_PERTURBATION:
            raise SceneError(
                "run.perturbation",
                f"got {size!r}; must lie in (0, {MAX_PERTURBATION:g}] (relative to each state's "
                "characteristic size, e.g. the clearance c for positions)",
            )
        out["perturbation"] = x
    return out


def _sweep_realisations(key: str, values: np.ndarray) -> None:
    """SceneError unless every value of a ``realisation`` sweep is an integer >= 0."""
    for i, v in enumerate(values):
        if not (math.isfinite(v) and v >= 0 and v == round(v)):
            raise SceneError(f"{key}[{i}]", f"got {float(v)!r}; a realisation is an integer >= 0")


def _validate_sweep(model, given: dict, effects) -> dict[str, tuple[float, ...]]:
    declared = {p.name: p for p in model.parameters}
    _unknown("sweep", given, {*declared, *RUN_SWEEP_KEYS})
    out = {}
    for k, spec in given.items():
        key = f"sweep.{k}"
        if isinstance(spec, Mapping):
            _unknown(key, spec, ("start", "stop", "num", "spacing"))
            for need in ("start", "stop", "num"):
                if need not in spec:
                    raise SceneError(f"{key}.{need}", "is required in a {start, stop, num} range")
            start = _number(f"{key}.start", spec["start"])
            stop = _number(f"{key}.stop", spec["stop"])
            num = _integer(f"{key}.num", spec["num"], 1)
            spacing = spec.get("spacing", "linear")
            if spacing == "linear":
                values = np.linspace(start, stop, num)
            elif spacing == "log":
                if start <= 0 or stop <= 0:
                    raise SceneError(
                        key, f"log spacing needs start, stop > 0, got {start!r}, {stop!r}"
                    )
                values = np.geomspace(start, stop, num)
            else:
                raise SceneError(f"{key}.spacing", f"got {spacing!r}; allowed: 'linear', 'log'")
        elif isinstance(spec, list | tuple):
            if not spec:
                raise SceneError(key, "must list at least one value")
            values = np.array([_number(f"{key}[{i}]", v) for i, v in enumerate(spec)])
        else:
            raise SceneError(key, f"must be a list of values or {{start, stop, num}}, got {spec!r}")
        if len(np.unique(values)) != len(values):
            raise SceneError(key, f"repeats a value: {list(values)!r}")
        if k in RUN_SWEEP_KEYS:
            _sweep_realisations(key, values)
            out[k] = tuple(float(v) for v in values)
            continue
        for i, v in enumerate(values):
            problem = declared[k].check(float(v))
            if problem:
                raise SceneError(f"{key}[{i}]", f"got {float(v)!r}; {problem}")
        out[k] = tuple(float(v) for v in values)
    return out
