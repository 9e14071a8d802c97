"""Scenes: the declarative description of a run (TOML), validated and frozen.

A scene has the tables ``[model]``, ``[effects]``, ``[parameters]``, ``[initial]``, ``[solver]``,
``[run]``, ``[record]`` and ``[sweep]`` (and optional top-level ``title`` and ``description``).
Every error names the offending key as a dotted path, shows the value and says what is allowed.

>>> from workbench.scene import load_scene, scene_from_toml
>>> s = load_scene({"model": {"name": "duffing"}, "parameters": {"gamma": 0.3}})
>>> s.parameters["gamma"], s.solver["method"]
(0.3, 'dop853')
>>> scene_from_toml(s.to_toml()) == s and load_scene(s) is s
True
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, TypeAlias

import tomli_w

from workbench._errors import SceneError
from workbench.models import available_models, get_model
from workbench.scene._modules import check_module_name, check_trusted, import_model_module
from workbench.scene._tables import (
    RUN_SWEEP_KEYS,
    finite,
    table,
    unknown_keys,
    validate_continuation,
    validate_effects,
    validate_ensemble,
    validate_parameters,
    validate_record,
    validate_run,
    validate_solver,
    validate_sweep,
)
from workbench.scene._text import check_nesting, parse_toml, read_scene_file

__all__ = ["Scene", "SceneSource", "load_scene", "scene_from_toml"]

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
    "mechanism",
)


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
    mechanism : Mapping
        The ``[mechanism]`` table of a declared mechanism (``model.name = "declared"``: a
        planar linkage declared as data, :mod:`workbench.models._declaration`), every field
        written; empty for any other model. :attr:`model` is then the name under which the
        declaration's model is registered (:func:`workbench.models._declared_model.declared_model`).
    model_module : str
        The module that defines a model of one's own (``[model] module``; imported, and so
        registered, when a scene given directly is loaded, and trusted for the rest of the
        process; stored text imports only a trusted module: see :func:`scene_from_toml` and
        ``docs/own-models.md``); '' for a built-in model.
    continuation : Mapping
        The ``[sweep]`` table's ``continuation`` settings, defaults filled in (empty: every point
        of the sweep starts from the scene's initial state; see :mod:`workbench.continuation`).
    title : str
        The top-level ``title`` ('' if none): the ``title`` attribute of the scene's runs and
        campaigns (without it, one that names the model).
    description : str
        The top-level ``description`` ('' if none): free text, kept in the scene's TOML (which
        every run and campaign stores in its ``scene`` attribute).
    """

    model: str
    effects: Mapping[str, Any]
    parameters: Mapping[str, float]
    initial: Mapping[str, float]
    solver: Mapping[str, Any]
    run: Mapping[str, Any]
    record: Mapping[str, Any]
    sweep: Mapping[str, tuple[float, ...]] = field(default_factory=lambda: _frozen({}))
    continuation: Mapping[str, Any] = field(default_factory=lambda: _frozen({}))
    title: str = ""
    description: str = ""
    model_module: str = ""
    mechanism: Mapping[str, Any] = field(default_factory=lambda: _frozen({}))

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
        d["model"] = {"name": DECLARED if self.mechanism else self.model}
        if self.mechanism:
            d["mechanism"] = dict(self.mechanism)
        if self.model_module:
            d["model"]["module"] = self.model_module
        for key in ("effects", "parameters", "initial", "solver", "run", "record"):
            values = {
                k: (list(v) if isinstance(v, tuple) else v) for k, v in getattr(self, key).items()
            }
            if key == "solver" and math.isinf(values.get("max_step", 0.0)):
                values.pop("max_step")
            if values:
                d[key] = values
        if self.sweep:
            d["sweep"] = {k: list(v) for k, v in self.sweep.items()}
            if self.continuation:
                d["sweep"]["continuation"] = dict(self.continuation)
        return d

    def to_toml(self) -> str:
        """TOML text that :func:`scene_from_toml` reads back to an equal scene."""
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


SceneSource: TypeAlias = "Scene | str | os.PathLike | Mapping[str, Any]"


# -- loading and validation ----------------------------------------------------------------------
def load_scene(source: SceneSource) -> Scene:
    """A validated scene from a Scene (returned as it is), a TOML file or a mapping.

    A scene given here is the user's own: the module its ``[model] module`` names is imported
    (after the rest of the scene that does not need the model is validated), from the normal
    import path, else beside the scene file or in the working directory (loaded by file path;
    the folder is not put on ``sys.path``). Stored text goes through :func:`scene_from_toml`,
    which imports nothing it is not told to trust.

    Parameters
    ----------
    source : Scene, str, PathLike or Mapping
        A scene; the path of a TOML file (any name, e.g. ``omega=2.toml``); or a mapping with
        the TOML structure. TOML *text* goes through :func:`scene_from_toml`.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        Naming the offending key (dotted path), its value and what is allowed; or the file
        that does not exist or is not TOML.
    """
    if isinstance(source, Scene):
        return source
    if isinstance(source, Mapping):
        return _validate(dict(check_nesting(source)), (Path.cwd(),))
    if not isinstance(source, str | os.PathLike):
        raise SceneError(
            "", f"a scene is a Scene, a TOML file path or a mapping; got {type(source).__name__}"
        )
    path = Path(source)
    try:
        found = path.is_file()
    except OSError:  # e.g. a name too long for a file: TOML text given by mistake
        found = False
    if not found:
        hint = (
            "; this looks like TOML text: read it with workbench.scene_from_toml(text)"
            if isinstance(source, str) and "\n" in source
            else ""
        )
        raise SceneError("", f"scene file {str(source)!r} does not exist{hint}")
    data = _parse(read_scene_file(path), repr(str(path)))
    return _validate(data, (path.resolve().parent, Path.cwd()))


def scene_from_toml(text: str, *, trust_modules: Iterable[str] = ()) -> Scene:
    """A validated scene from TOML text (e.g. a stored run's ``scene`` attribute).

    Stored text runs no code: a scene that names a ``[model] module`` is refused unless that
    module is trusted, by ``trust_modules`` or because it was imported on the user's word
    earlier in this process (a scene file or mapping given to :func:`load_scene` that names
    it). A trusted module is imported like :func:`load_scene` does it, from the normal import
    path or the working directory.

    Parameters
    ----------
    text : str
        TOML text of a scene.
    trust_modules : str or iterable of str
        Modules the text may name and so import (command line: ``--trust-module NAME``).

    Raises
    ------
    SceneError
        If the text is not TOML or the scene is invalid (naming the key), or names a module
        that is not trusted (naming the module and how to trust it).
    """
    trusted = (trust_modules,) if isinstance(trust_modules, str) else tuple(trust_modules)
    return _validate(_parse(text, "the scene text"), (Path.cwd(),), trusted)


def _parse(text: str, where: str) -> dict[str, Any]:
    return parse_toml(text, where)


def _validate(
    data: Mapping[str, Any], directories: tuple[Path, ...], trusted: tuple[str, ...] | None = None
) -> Scene:
    """The scene of ``data``. Everything that does not need the model (the tables, their types,
    the solver, the model's name and module name) is checked before the module ``[model]
    module`` is imported: from ``directories`` if not on the import path, and only if
    ``trusted`` is None (the user's own scene) or it is trusted (stored text)."""
    unknown_keys("", data, _TABLES)
    for key in ("title", "description"):
        if key in data and not isinstance(data[key], str):
            raise SceneError(key, f"must be a string, got {data[key]!r}")
    model_t = table(data, "model")
    unknown_keys("model", model_t, ("name", "module"))
    tables = {k: table(data, k) for k in _TABLES[3:]}
    solver = validate_solver(tables["solver"])
    name = model_t.get("name")
    mechanism: dict[str, Any] = {}
    if "mechanism" in data or name == DECLARED:
        name, mechanism = _declared(name, data)
    if name is None:
        raise SceneError(
            "model.name", "is required; available models: " + ", ".join(available_models())
        )
    module = ""
    if "module" in model_t:
        module = check_module_name(model_t["module"])
        if trusted is not None:
            check_trusted(module, trusted)
        import_model_module(module, directories)
    if name not in available_models():
        raise SceneError(
            "model.name", f"unknown model {name!r}; available: {', '.join(available_models())}"
        )
    model = get_model(name)

    effects = validate_effects(model, tables["effects"])
    parameters = validate_parameters(model, tables["parameters"], "parameters")
    resolved = model.default_parameters()
    resolved.update(parameters)
    model.validate(resolved, effects)

    states = {q.name for q in model.states(effects)}
    initial_t = tables["initial"]
    unknown_keys("initial", initial_t, states)
    initial = {k: finite(f"initial.{k}", v) for k, v in initial_t.items()}

    period = model.forcing_period(resolved)
    run_t = tables["run"]
    ensemble = validate_ensemble(run_t)  # takes its keys out of run_t
    run = validate_run(run_t, period is not None) | ensemble
    record = validate_record(tables["record"], model, effects, period is not None, run)
    sweep_t = tables["sweep"]
    continuation_t = sweep_t.pop("continuation", None)
    sweep = validate_sweep(model, sweep_t, effects)
    continuation = (
        {} if continuation_t is None else validate_continuation(continuation_t, sweep, run)
    )
    return Scene(
        model=name,
        effects=_frozen(effects),
        parameters=_frozen(parameters),
        initial=_frozen(initial),
        solver=_frozen(solver),
        run=_frozen(run),
        record=_frozen(record),
        sweep=_frozen(sweep),
        continuation=_frozen(continuation),
        title=data.get("title", ""),
        description=data.get("description", ""),
        model_module=module,
        mechanism=_frozen(mechanism),
    )


#: the ``model.name`` of a scene that declares its mechanism in a ``[mechanism]`` table
DECLARED = "declared"


def _declared(name: str | None, data: Mapping[str, Any]) -> tuple[str, dict[str, Any]]:
    """The registered name of the model that a scene's ``[mechanism]`` table declares, and the
    table with every field written."""
    from workbench.models._declaration import to_table
    from workbench.models._declare import parse_mechanism
    from workbench.models._declared_model import declared_model

    if "mechanism" not in data:
        raise SceneError(
            "model.name", f"got {DECLARED!r} without a [mechanism] table; declare the mechanism"
        )
    if name not in (None, DECLARED):
        raise SceneError(
            "model.name",
            f"got {name!r} with a [mechanism] table; a scene that declares its mechanism has "
            f"model.name = {DECLARED!r} (or no [model] table)",
        )
    linkage = parse_mechanism(data["mechanism"])
    return declared_model(linkage).name, to_table(linkage)
