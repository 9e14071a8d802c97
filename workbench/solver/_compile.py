"""Specialise compiled templates for one model.

Numba cannot cache a compiled function that receives other compiled functions as arguments or
closes over them (its cache then recompiles every process, seconds each time). Instead a template
(the integration loop :mod:`workbench.solver._kernel` with the steps it takes,
:mod:`workbench.solver._steps_template` and :mod:`workbench.solver._implicit_template`, the
Jacobian :mod:`workbench.solver._jacobian_template`, the tangent system
:mod:`workbench.solver._tangent_template`, side-by-side copies
:mod:`workbench.solver._copies_template`) is written once per model into the cache directory
with its hook imports pointing at the model's module, and imported from there as a module of the
package ``workbench_kernels`` (:data:`workbench._cache.KERNEL_PACKAGE`): an ordinary module
whose functions call global compiled functions,
which numba caches on disk. Every process after the first (a CLI call, a dask worker) loads
machine code instead of compiling.
"""

from __future__ import annotations

import importlib
import os
import re
import sys
import types
from functools import cache
from pathlib import Path
from types import ModuleType

from workbench._cache import KERNEL_PACKAGE, kernel_directory
from workbench._sources import source_digest

_HERE = Path(__file__).parent
# read at import: the generated modules are these texts (their digest keys their names)
_SOURCES = {
    name: (_HERE / f"{name}.py").read_text()
    for name in (
        "_kernel",
        "_steps_template",
        "_implicit_template",
        "_jacobian_template",
        "_tangent_template",
        "_copies_template",
    )
}
_PLACEHOLDER = "workbench.solver._hooks_template"
# the modules whose text the generated kernels are made of (read, not imported: code digests of
# results name them, see workbench.run.results_digest)
TEMPLATE_MODULES = tuple(f"{__package__}.{name}" for name in _SOURCES)


def _directory() -> Path:
    directory = kernel_directory()
    directory.mkdir(parents=True, exist_ok=True)
    if KERNEL_PACKAGE not in sys.modules:
        # a namespace for the generated modules, so that they import each other by name
        package = types.ModuleType(KERNEL_PACKAGE)
        package.__path__ = [str(directory)]
        sys.modules[KERNEL_PACKAGE] = package
    return directory


def _substitute(source: str, marker: str, module: str) -> str:
    """Point the import lines tagged ``# @@<marker>@@`` at ``module`` (the names they import
    stay)."""
    pattern = re.compile(rf"^from \S+ import (.*)  # @@{marker}@@$", re.M)
    source, n = pattern.subn(rf"from {module} import \1  # generated", source)
    if n == 0:  # pragma: no cover - guards an edit of a template
        raise RuntimeError(f"marker @@{marker}@@ not found in a template")
    return source


def _label(hooks: str) -> str:
    """The readable part of a generated module's name: a model's module name, or the label of
    a generated hooks module (its digest dropped)."""
    if hooks.startswith(KERNEL_PACKAGE + "."):
        return hooks[len(KERNEL_PACKAGE) + 1 :].rsplit("_", 1)[0]
    return re.sub(r"\W", "_", hooks)


def _specialise(template: str, prefix: str, hooks: str, modules: dict, flags=None) -> ModuleType:
    """Write ``template`` with its tagged import lines pointed at ``modules`` (marker -> module)
    and its tagged flags set (``flags``: name -> bool) as module
    ``workbench_kernels.<prefix>_<label>_<digest>`` (the digest of its code and of everything it
    imports, :func:`workbench._sources.source_digest`), and import it."""
    source = _SOURCES[template]
    for marker, module in modules.items():
        source = _substitute(source, marker, module)
    for flag, value in (flags or {}).items():
        pattern = re.compile(rf"^{flag} = \w+  # @@FLAG@@$", re.M)
        source, n = pattern.subn(f"{flag} = {bool(value)}  # generated", source)
        if n != 1:  # pragma: no cover
            raise RuntimeError(f"flag {flag} not found exactly once in {template}")
    directory = _directory()
    label = f"{prefix}_{_label(hooks)}"
    name = f"{label}_{source_digest(source, f'{KERNEL_PACKAGE}.{label}')}"
    path = directory / f"{name}.py"
    if not path.exists() or path.read_text() != source:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(source)
        os.replace(tmp, path)  # atomic: concurrent workers never see a half-written file
    return importlib.import_module(f"{KERNEL_PACKAGE}.{name}")


@cache
def kernel_for(hooks: str) -> ModuleType:
    """The compiled integration loop whose hooks come from module ``hooks``.

    Parameters
    ----------
    hooks : str
        Importable module name defining ``rhs``, ``event_values`` and ``apply_event``.
    """
    steps = _specialise("_steps_template", "steps", hooks, {"HOOKS": hooks}).__name__
    jacobian = jacobian_for(hooks).__name__
    implicit = _specialise(
        "_implicit_template",
        "implicit",
        hooks,
        {"HOOKS": hooks, "JACOBIAN": jacobian, "STEPS": steps},
    ).__name__
    modules = {"HOOKS": hooks, "STEPS": steps, "IMPLICIT": implicit}
    return _specialise("_kernel", "kernel", hooks, modules)


@cache
def jacobian_for(hooks: str) -> ModuleType:
    """The compiled Jacobian ``jacobian(t, y, p, ip, aux, work, J)`` of the model whose hooks
    are in module ``hooks``: the module's own analytic ``jacobian`` if it defines one, else
    central finite differences of its compiled ``rhs`` (``fd_jacobian``, always available, so
    that an analytic Jacobian can be checked against it). See
    :mod:`workbench.solver._jacobian_template`.
    """
    analytic = _defines_jacobian(importlib.import_module(hooks))
    modules = {"HOOKS": hooks, "JACOBIAN": hooks if analytic else _PLACEHOLDER}
    flags = {"HAS_ANALYTIC": analytic}
    return _specialise("_jacobian_template", "jacobian", hooks, modules, flags)


def _defines_jacobian(module: ModuleType) -> bool:
    """Whether ``module`` defines its own ``jacobian`` hook (a derived system's module may
    import another module's ``jacobian`` under that name, e.g. the tangent system)."""
    fn = getattr(module, "jacobian", None)
    py_func = getattr(fn, "py_func", fn)
    return fn is not None and getattr(py_func, "__module__", None) == module.__name__


@cache
def tangent_for(hooks: str) -> ModuleType:
    """Hooks of the tangent (variational) system of the model whose hooks are in ``hooks``, with
    saltation at events; see :mod:`workbench.solver._tangent_template`. Integrate it with
    ``kernel_for(tangent_for(hooks).__name__)``."""
    modules = {"HOOKS": hooks, "MODEL_JACOBIAN": jacobian_for(hooks).__name__}
    return _specialise("_tangent_template", "tangent", hooks, modules)


@cache
def copies_for(hooks: str) -> ModuleType:
    """Hooks of several copies of the model whose hooks are in ``hooks``, integrated side by
    side with one step-size sequence; see :mod:`workbench.solver._copies_template`."""
    return _specialise("_copies_template", "copies", hooks, {"HOOKS": hooks})
