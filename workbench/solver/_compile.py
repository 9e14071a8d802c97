"""Generate and load the compiled code of one model from the templates.

Numba cannot cache a compiled function that receives other compiled functions as arguments or
closes over them (its cache then recompiles every process, seconds each time). Instead each
template of :mod:`workbench.solver._templates` (real, importable, lintable Python) is written
once per model into the cache directory with its tagged import lines (``# @@HOOKS@@``, ...)
pointing at the model's module and at the other generated modules, and executed as a module of
the package ``workbench_kernels`` (:data:`workbench._cache.KERNEL_PACKAGE`): an ordinary module
whose functions call global compiled functions, which numba caches on disk (and loads only as
:mod:`workbench._cache` checks it). Every process after the first (a CLI call, a dask worker)
loads machine code instead of compiling. A generated module is executed from the text generated
in this process, never read back from the cache folder, which the import system does not search
either (a package, a ``.py`` or a ``.pyc`` planted there is not imported); its file is written
for numba and tracebacks.

What is generated, for hooks module ``H`` (a model's ``rhs``, ``event_values``,
``apply_event``, optional ``jacobian`` and ``step_end``; a loop whose hooks have no ``step_end``
is compiled without the call, flag ``HAS_STEP_END``):

========================  =================================  ==================================
function                  template                           generates
========================  =================================  ==================================
:func:`kernel_for`        ``integration_loop``               the loop (``advance``), with
                          ``explicit_steps``, ``radau_step``  the steps of every method
:func:`jacobian_for`      ``jacobian``                       H's Jacobian (analytic or FD)
:func:`tangent_for`       ``tangent_hooks``                  hooks of H's variational system
:func:`copies_for`        ``copies_hooks``                   hooks of copies of H side by side
========================  =================================  ==================================

:func:`generated_source` prints what was written for a model.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import linecache
import os
import re
import stat
import sys
import tempfile
import threading
import types
import warnings
from functools import cache
from pathlib import Path
from types import ModuleType

from workbench._cache import (
    KERNEL_PACKAGE,
    CacheError,
    CacheWarning,
    kernel_directory,
    read_regular,
)
from workbench._sources import parse, source_digest

_TEMPLATES = Path(__file__).parent / "_templates"
# read at import: the generated modules are these texts (their digest keys their names)
_SOURCES = {
    name: (_TEMPLATES / f"{name}.py").read_text()
    for name in (
        "integration_loop",
        "explicit_steps",
        "radau_step",
        "jacobian",
        "tangent_hooks",
        "copies_hooks",
    )
}
_PLACEHOLDER = "workbench.solver._templates.placeholder_hooks"
# the modules whose text the generated kernels are made of (read, not imported: code digests of
# results name them, see workbench.run.results_digest)
TEMPLATE_MODULES = tuple(f"{__package__}._templates.{name}" for name in _SOURCES)


def _directory() -> Path:
    directory = kernel_directory()  # the checked cache root: CacheError if refused
    directory.mkdir(exist_ok=True)
    if KERNEL_PACKAGE not in sys.modules:
        # a namespace for the generated modules, so that they import each other by name; its
        # path is empty: a module is found in sys.modules (put there by _load) or not at all
        package = types.ModuleType(KERNEL_PACKAGE)
        package.__path__ = []
        package.directory = str(directory)  # where the files are (workbench._sources)
        sys.modules[KERNEL_PACKAGE] = package
    return directory


_LOADING = threading.RLock()  # one thread at a time writes and executes a generated module
_GENERATED: dict[str, str] = {}  # the text of each generated module of this process, by path


def _write(path: Path, source: str) -> None:
    """Write ``source`` at ``path`` unless a regular file there holds it already (atomically:
    concurrent workers or threads never see half a file); a folder there is refused."""
    data = source.encode()
    try:
        if read_regular(path) == data:
            return
    except OSError:  # a link, a FIFO, ...: replaced below; a folder: refused
        if stat.S_ISDIR(os.lstat(path).st_mode):
            raise CacheError(
                f"{path} is a folder where workbench writes a generated kernel module; "
                "remove it (workbench never imports it)"
            ) from None
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}-", suffix=".tmp")
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    os.chmod(tmp, 0o644)
    os.replace(tmp, path)


def _load(name: str, path: Path, source: str) -> ModuleType:
    """Module ``workbench_kernels.<name>`` executed from ``source`` (written at ``path`` first),
    or the one this process already has."""
    qualified = f"{KERNEL_PACKAGE}.{name}"
    with _LOADING:
        module = sys.modules.get(qualified)
        if module is not None:
            return module
        _write(path, source)
        if (path.parent / name).is_dir():
            warnings.warn(
                CacheWarning(
                    f"{path.parent / name} is a folder named like the generated module "
                    f"{path.name}: ignored (workbench imports only the module it generates)"
                ),
                stacklevel=4,
            )
        spec = importlib.util.spec_from_loader(qualified, loader=None, origin=str(path))
        module = importlib.util.module_from_spec(spec)
        module.__file__ = str(path)
        code = compile(source, str(path), "exec", dont_inherit=True)
        # tracebacks and inspect show the executed text, whatever the file holds later
        linecache.cache[str(path)] = (len(source), None, source.splitlines(True), str(path))
        _GENERATED[str(path)] = source
        sys.modules[qualified] = module
        try:
            exec(code, module.__dict__)
        except BaseException:
            del sys.modules[qualified]
            raise
        setattr(sys.modules[KERNEL_PACKAGE], name, module)
        return module


def _substitute(source: str, marker: str, module: str) -> str:
    """Point every import statement tagged ``# @@<marker>@@`` (on any of its lines: a formatter
    may wrap it) at ``module``; the names it imports stay. Every tag must belong to an import
    statement, and the tag becomes ``# generated``."""
    tag = f"# @@{marker}@@"
    lines = source.splitlines(keepends=True)
    tagged = {i for i, line in enumerate(lines) if line.rstrip().endswith(tag)}
    rewritten = set()
    for node in ast.walk(parse(source)):
        if not isinstance(node, ast.ImportFrom):
            continue
        span = set(range(node.lineno - 1, node.end_lineno))
        if span & tagged:
            first = node.lineno - 1
            lines[first] = re.sub(r"^from \S+ import", f"from {module} import", lines[first])
            rewritten |= span & tagged
    if not tagged or rewritten != tagged:  # pragma: no cover - guards an edit of a template
        raise RuntimeError(
            f"marker @@{marker}@@ not found on an import statement of a template "
            f"(lines {sorted(i + 1 for i in tagged - rewritten) or 'none'})"
        )
    for i in tagged:
        lines[i] = lines[i].replace(tag, "# generated")
    return "".join(lines)


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
    imports, :func:`workbench._sources.source_digest`), and execute it (:func:`_load`)."""
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
    return _load(name, directory / f"{name}.py", source)


def kernel_for(hooks: str) -> ModuleType:
    """The compiled integration loop whose hooks come from module ``hooks``.

    Parameters
    ----------
    hooks : str
        Importable module name defining ``rhs``, ``event_values`` and ``apply_event``.
    """
    return _kernel_parts(hooks)["kernel"]


@cache
def _kernel_parts(hooks: str) -> dict[str, ModuleType]:
    """The generated modules of the integration loop of ``hooks``: its explicit steps
    (``steps``), Radau IIA's step (``implicit``) and the loop itself (``kernel``)."""
    steps = _specialise("explicit_steps", "steps", hooks, {"HOOKS": hooks})
    jacobian = jacobian_for(hooks).__name__
    implicit = _specialise(
        "radau_step",
        "implicit",
        hooks,
        {"HOOKS": hooks, "JACOBIAN": jacobian, "STEPS": steps.__name__},
    )
    step_end = defines_hook(importlib.import_module(hooks), "step_end")
    modules = {"HOOKS": hooks, "STEPS": steps.__name__, "IMPLICIT": implicit.__name__}
    modules["STEP_END"] = hooks if step_end else "workbench.solver._no_events"  # a no-op
    flags = {"HAS_STEP_END": step_end}
    kernel = _specialise("integration_loop", "kernel", hooks, modules, flags)
    return {"steps": steps, "implicit": implicit, "kernel": kernel}


@cache
def jacobian_for(hooks: str) -> ModuleType:
    """The compiled Jacobian ``jacobian(t, y, p, ip, aux, work, J)`` of the model whose hooks
    are in module ``hooks``: the module's own analytic ``jacobian`` if it defines one, else
    central finite differences of its compiled ``rhs`` (``fd_jacobian``, always available, so
    that an analytic Jacobian can be checked against it). See
    :mod:`workbench.solver._templates.jacobian`.
    """
    analytic = defines_hook(importlib.import_module(hooks), "jacobian")
    modules = {"HOOKS": hooks, "JACOBIAN": hooks if analytic else _PLACEHOLDER}
    flags = {"HAS_ANALYTIC": analytic}
    return _specialise("jacobian", "jacobian", hooks, modules, flags)


def defines_hook(module: ModuleType, hook: str) -> bool:
    """Whether ``module`` defines its own optional hook ``hook`` (``jacobian``, ``step_end``; a
    derived system's module may import another module's ``jacobian`` under that name, e.g. the
    tangent system)."""
    fn = getattr(module, hook, None)
    py_func = getattr(fn, "py_func", fn)
    return fn is not None and getattr(py_func, "__module__", None) == module.__name__


@cache
def tangent_for(hooks: str) -> ModuleType:
    """Hooks of the tangent (variational) system of the model whose hooks are in ``hooks``, with
    saltation at events; see :mod:`workbench.solver._templates.tangent_hooks`. Integrate it with
    ``kernel_for(tangent_for(hooks).__name__)``."""
    modules = {"HOOKS": hooks, "MODEL_JACOBIAN": jacobian_for(hooks).__name__}
    return _specialise("tangent_hooks", "tangent", hooks, modules)


@cache
def copies_for(hooks: str) -> ModuleType:
    """Hooks of several copies of the model whose hooks are in ``hooks``, integrated side by
    side with one step-size sequence; see :mod:`workbench.solver._templates.copies_hooks`."""
    return _specialise("copies_hooks", "copies", hooks, {"HOOKS": hooks})


def generated_source(hooks: str, what: str = "kernel") -> tuple[Path, str]:
    """The path and text of the module generated for hooks module ``hooks``: ``what`` =
    ``"kernel"`` (the integration loop), ``"steps"`` (its explicit steps), ``"implicit"``
    (Radau IIA's step), ``"jacobian"`` or ``"tangent"`` (the variational system's hooks).
    Generates it if needed (compiles nothing).

    >>> path, text = generated_source("workbench.models.duffing", "jacobian")
    >>> "from workbench.models.duffing import" in text
    True
    """
    if what in ("kernel", "steps", "implicit"):
        module = _kernel_parts(hooks)[what]
    elif what in ("jacobian", "tangent"):
        module = (jacobian_for if what == "jacobian" else tangent_for)(hooks)
    else:
        raise ValueError(f"what: got {what!r}; allowed: kernel, steps, implicit, jacobian, tangent")
    return Path(module.__file__), _GENERATED[module.__file__]
