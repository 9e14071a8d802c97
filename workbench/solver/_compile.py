"""Specialise the compiled integration loop for one model.

Numba cannot cache a compiled function that receives other compiled functions as arguments or
closes over them (its cache then recompiles every process, seconds each time). Instead the kernel
source (:mod:`workbench.solver._kernel`) is written once per model into the cache directory with
its hook import pointing at the model's module, and imported from there: an ordinary module whose
functions call global compiled functions, which numba caches on disk. Every process after the
first (a CLI call, a dask worker) loads machine code instead of compiling.
"""

from __future__ import annotations

import importlib.util
import os
import re
import sys
from functools import cache
from pathlib import Path
from types import ModuleType

from workbench._cache import KERNEL_PACKAGE, kernel_directory

_TEMPLATE = Path(__file__).with_name("_kernel.py")
# read at import, like the package digest that keys the cache, so that both describe one source
_TEMPLATE_SOURCE = _TEMPLATE.read_text()
_MARKER = re.compile(r"^from .* import apply_event, event_values, rhs  # @@HOOKS@@$", re.M)


@cache
def kernel_for(hooks: str) -> ModuleType:
    """The compiled integration loop whose hooks come from module ``hooks``.

    Parameters
    ----------
    hooks : str
        Importable module name defining ``rhs``, ``event_values`` and ``apply_event``.
    """
    source = _TEMPLATE_SOURCE
    line = f"from {hooks} import apply_event, event_values, rhs  # generated"
    source, n = _MARKER.subn(line, source)
    if n != 1:  # pragma: no cover - guards an edit of the template
        raise RuntimeError(f"hook marker not found exactly once in {_TEMPLATE}")
    directory = kernel_directory()
    directory.mkdir(parents=True, exist_ok=True)
    name = "kernel_" + re.sub(r"\W", "_", hooks)
    path = directory / f"{name}.py"
    if not path.exists() or path.read_text() != source:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(source)
        os.replace(tmp, path)  # atomic: concurrent workers never see a half-written file
    module_name = f"{KERNEL_PACKAGE}.{name}"
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module
    spec.loader.exec_module(module)
    return module
