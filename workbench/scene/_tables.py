"""Validation of a scene's tables: each function checks one table and fills in its defaults.

Every error names the offending key as a dotted path, shows the value and says what is allowed.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from workbench._errors import SceneError
from workbench.solver import METHODS

__all__ = [
    "finite",
    "number",
    "table",
    "unknown_keys",
    "validate_effects",
    "validate_parameters",
    "validate_record",
    "validate_run",
    "validate_solver",
    "validate_sweep",
]

_SOLVER_DEFAULTS = {
    "method": "dop853",
    "rtol": 1e-8,
    "atol": 1e-10,
    "max_step": math.inf,
    "max_steps": 50_000_000,
    "check": False,
}


def table(data: Mapping, key: str) -> dict:
    """The table ``key`` of ``data`` (empty if absent) as a new dict."""
    value = data.get(key, {})
    if not isinstance(value, Mapping):
        raise SceneError(key, f"must be a table, got {value!r}")
    return dict(value)


def number(key: str, value: Any) -> float:
    """``value`` as a float; SceneError naming ``key`` if it is not a number."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise SceneError(key, f"must be a number, got {value!r}")
    return float(value)


def finite(key: str, value: Any) -> float:
    """``value`` as a finite float; SceneError naming ``key`` if it is not one."""
    x = number(key, value)
    if not math.isfinite(x):
        raise SceneError(key, f"got {value!r}; must be a finite number")
    return x


#: the largest integer a scene accepts (the compiled loop counts in int64)
MAX_INTEGER = 2**62


def integer(key: str, value: Any, minimum: int) -> int:
    allowed = f"must be an integer in [{minimum}, 2**62]"
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise SceneError(key, f"{allowed}, got {value!r}")
    if not minimum <= value <= MAX_INTEGER:
        raise SceneError(key, f"{allowed}, got {value!r}")
    return int(value)


def positive(key: str, value: Any, *, allow_inf: bool = False) -> float:
    x = number(key, value)
    if not (x > 0) or (math.isinf(x) and not allow_inf) or math.isnan(x):
        raise SceneError(
            key, f"must be a positive{' ' if allow_inf else ' finite '}number, got {value!r}"
        )
    return x


def unknown_keys(table: str, given: Mapping, allowed) -> None:
    """SceneError naming the first key of ``given`` not in ``allowed`` (table ``table``)."""
    for k in given:
        if k not in allowed:
            names = ", ".join(sorted(allowed)) or "(none)"
            raise SceneError(f"{table}.{k}" if table else k, f"unknown key; allowed: {names}")


def validate_effects(model, given: dict) -> dict:
    declared = {e.name: e for e in model.effects}
    unknown_keys("effects", given, declared)
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


def validate_parameters(model, given: dict, table: str) -> dict[str, float]:
    declared = {p.name: p for p in model.parameters}
    unknown_keys(table, given, declared)
    out = {}
    for k, v in given.items():
        x = number(f"{table}.{k}", v)
        problem = declared[k].check(x)
        if problem:
            raise SceneError(f"{table}.{k}", f"got {v!r}; {problem}")
        out[k] = x
    return out


def validate_solver(given: dict) -> dict:
    """The ``[solver]`` table with defaults filled in."""
    unknown_keys("solver", given, _SOLVER_DEFAULTS)
    s = dict(_SOLVER_DEFAULTS)
    s.update(given)
    method = s["method"]
    allowed = METHODS
    if not isinstance(method, str) or method not in allowed:
        raise SceneError("solver.method", f"got {method!r}; allowed: {', '.join(allowed)}")
    s["rtol"] = positive("solver.rtol", s["rtol"])
    if not 1e-14 <= s["rtol"] < 1:
        raise SceneError("solver.rtol", f"got {s['rtol']!r}; must lie in [1e-14, 1)")
    s["atol"] = positive("solver.atol", s["atol"])
    s["max_step"] = positive("solver.max_step", s["max_step"], allow_inf=True)
    s["max_steps"] = integer("solver.max_steps", s["max_steps"], 1)
    if not isinstance(s["check"], bool):
        raise SceneError(
            "solver.check",
            f"got {s['check']!r}; allowed: true or false (estimate the run's own "
            "error by a second run 100x tighter over the first period)",
        )
    return s


#: ``[run]`` keys of an ensemble (see :mod:`workbench.run._ensemble`)
ENSEMBLE_KEYS = ("realisation", "perturbation")
#: ``[run]`` keys a ``[sweep]`` may list
RUN_SWEEP_KEYS = ("realisation",)
#: largest relative initial-state perturbation of an ensemble: it models round-off and unknown
#: initial conditions, not another initial state (that is ``[initial]``)
MAX_PERTURBATION = 1e-2


def validate_ensemble(run: dict) -> dict:
    """Take the ensemble keys ``realisation`` and ``perturbation`` out of the ``[run]`` table
    ``run`` and validate them; returns those given."""
    out: dict[str, Any] = {}
    if "realisation" in run:
        out["realisation"] = integer("run.realisation", run.pop("realisation"), 0)
    if "perturbation" in run:
        size = run.pop("perturbation")
        x = number("run.perturbation", size)
        if not 0 < x <= MAX_PERTURBATION:
            raise SceneError(
                "run.perturbation",
                f"got {size!r}; must lie in (0, {MAX_PERTURBATION:g}] (relative to each state's "
                "characteristic size, e.g. the clearance c for positions)",
            )
        out["perturbation"] = x
    return out


def validate_run(given: dict, forced: bool) -> dict:
    if forced:
        unknown_keys(
            "run", given, ("cycles", "transient_cycles", "duration", "transient", *ENSEMBLE_KEYS)
        )
        if "cycles" in given or "transient_cycles" in given or not given:
            if "duration" in given or "transient" in given:
                raise SceneError(
                    "run", "give either cycles/transient_cycles or duration/transient, not both"
                )
            return {
                "cycles": integer("run.cycles", given.get("cycles", 10), 1),
                "transient_cycles": integer(
                    "run.transient_cycles", given.get("transient_cycles", 0), 0
                ),
            }
    else:
        for k in ("cycles", "transient_cycles"):
            if k in given:
                raise SceneError(
                    f"run.{k}", "this model has no forcing period; use run.duration (s) instead"
                )
        unknown_keys("run", given, ("duration", "transient", *ENSEMBLE_KEYS))
    if "duration" not in given:
        raise SceneError("run.duration", "is required (simulated time to record, s)")
    transient = number("run.transient", given.get("transient", 0.0))
    if not (0 <= transient < math.inf):  # NaN fails it too
        raise SceneError("run.transient", f"must be a finite number >= 0 s, got {transient!r}")
    return {"duration": positive("run.duration", given["duration"]), "transient": transient}


def validate_record(given: dict, model, effects, forced: bool, run: dict) -> dict:
    unknown_keys("record", given, ("samples_per_period", "dt", "variables"))
    rec: dict[str, Any] = {}
    if "samples_per_period" in given and "dt" in given:
        raise SceneError("record", "give either samples_per_period or dt, not both")
    if "samples_per_period" in given:
        if not forced:
            raise SceneError(
                "record.samples_per_period", "this model has no forcing period; use record.dt (s)"
            )
        rec["samples_per_period"] = integer(
            "record.samples_per_period", given["samples_per_period"], 1
        )
    elif "dt" in given:
        rec["dt"] = positive("record.dt", given["dt"])
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
    # what every run with these effects records (e.g. LuGre's friction-law diagnostics)
    variables = [*variables, *(v for v in model.recorded_always(effects) if v not in variables)]
    rec["variables"] = tuple(variables)
    return rec


def validate_sweep(model, given: dict, effects) -> dict[str, tuple[float, ...]]:
    declared = {p.name: p for p in model.parameters}
    unknown_keys("sweep", given, {*declared, *RUN_SWEEP_KEYS})
    out = {}
    for k, spec in given.items():
        key = f"sweep.{k}"
        if isinstance(spec, Mapping):
            unknown_keys(key, spec, ("start", "stop", "num", "spacing"))
            for need in ("start", "stop", "num"):
                if need not in spec:
                    raise SceneError(f"{key}.{need}", "is required in a {start, stop, num} range")
            start = number(f"{key}.start", spec["start"])
            stop = number(f"{key}.stop", spec["stop"])
            num = integer(f"{key}.num", spec["num"], 1)
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
            values = np.array([number(f"{key}[{i}]", v) for i, v in enumerate(spec)])
        else:
            raise SceneError(key, f"must be a list of values or {{start, stop, num}}, got {spec!r}")
        if len(np.unique(values)) != len(values):
            raise SceneError(key, f"repeats a value: {list(values)!r}")
        if k in RUN_SWEEP_KEYS:
            for i, v in enumerate(values):
                if not (math.isfinite(v) and v >= 0 and v == round(v)):
                    raise SceneError(
                        f"{key}[{i}]", f"got {float(v)!r}; a realisation is an integer >= 0"
                    )
            out[k] = tuple(float(v) for v in values)
            continue
        for i, v in enumerate(values):
            problem = declared[k].check(float(v))
            if problem:
                raise SceneError(f"{key}[{i}]", f"got {float(v)!r}; {problem}")
        out[k] = tuple(float(v) for v in values)
    return out
