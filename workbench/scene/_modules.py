"""The module of a model of one's own (``[model] module``): which modules a process may import,
and importing one without letting a scene's folder shadow installed libraries.

Importing a module runs its code, so a module is imported only when the user named it: in a
scene passed directly (a scene file, a mapping or a :class:`~workbench.Scene` given to the API,
a scene file on the command line), or explicitly (``trust_modules=`` of
:func:`~workbench.scene_from_toml`, ``--trust-module`` on the command line). A scene rebuilt
from stored text (an archive's ``scene`` attribute, a campaign's manifest) that names any other
module is refused before anything is imported (:func:`check_trusted`). The modules trusted so
far are remembered for the life of the process: a module already imported on the user's word
is not imported again, so stored text naming it runs no code.

The module is looked up on the normal import path first; only if it is not there, the file
``NAME.py`` (or the package ``NAME/__init__.py``) beside the scene file or in the working
directory is loaded by its path (:func:`importlib.util.spec_from_file_location`) and registered
in ``sys.modules`` under its name, the name the generated kernel imports its hooks by. The
folder is never put on ``sys.path``: a ``netCDF4.py`` lying beside a shared scene cannot take
the place of the installed library.
"""

from __future__ import annotations

import importlib
import importlib.util
import keyword
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from workbench._errors import SceneError

__all__ = ["check_module_name", "check_trusted", "import_model_module", "is_trusted"]

_KEY = "model.module"
# modules imported on the user's word in this process (a scene given directly, trust_modules)
_TRUSTED: set[str] = set()


def check_module_name(value: Any) -> str:
    """``value`` if it is a dotted Python module name (identifiers joined by dots, no keyword),
    else SceneError naming ``model.module``, the value and the rule."""
    parts = value.split(".") if isinstance(value, str) else [""]
    if not all(p.isidentifier() and not keyword.iskeyword(p) for p in parts):
        raise SceneError(
            _KEY,
            f"must be a module name: Python identifiers joined by dots (e.g. 'rossler_model' "
            f"or 'mypackage.models'), got {value!r}",
        )
    return value


def is_trusted(module: str) -> bool:
    """Whether ``module`` was imported on the user's word in this process."""
    return module in _TRUSTED


def check_trusted(module: str, trust_modules: Iterable[str]) -> None:
    """SceneError unless ``module``, named by a scene rebuilt from stored text, is trusted: in
    ``trust_modules`` or imported on the user's word earlier in this process. The message names
    the module and the explicit ways to trust it."""
    if module in _TRUSTED or module in set(trust_modules):
        return
    raise SceneError(
        _KEY,
        f"the scene text names the module {module!r}; a scene read from stored text (an "
        "archive's or a manifest's) imports no module, since importing runs its code. If you "
        f"trust {module!r}: scene_from_toml(text, trust_modules=({module!r},)) (workbench "
        f"analyse: --trust-module {module}), or load the scene file that names it",
    )


def import_model_module(module: str, directories: Iterable[Path] = ()) -> str:
    """Import ``module``, which the user named (its import registers the model), and trust it
    for the rest of the process: from the normal import path, else from the first of
    ``directories`` that holds ``TOP.py`` or ``TOP/__init__.py`` (``TOP`` the first part of the
    name), loaded by file path without touching ``sys.path``.

    Raises
    ------
    SceneError
        The name is malformed, the module is nowhere to be found, or it fails to import a
        module it needs.
    """
    check_module_name(module)
    if module in _TRUSTED and module in sys.modules:
        return module
    top = module.split(".")[0]
    try:
        if top not in sys.modules and importlib.util.find_spec(top) is None:
            _load_by_path(module, top, list(directories))
        importlib.import_module(module)
    except ModuleNotFoundError as exc:
        raise SceneError(_KEY, f"importing {module!r} failed: {exc}") from None
    _TRUSTED.add(module)
    return module


def _load_by_path(module: str, top: str, directories: list[Path]) -> None:
    """Load the top-level module ``top`` from the first directory holding it, by file path,
    registered in ``sys.modules`` as ``top`` (a package keeps its folder as its ``__path__``,
    so that its submodules import)."""
    for where in directories:
        package, file = where / top / "__init__.py", where / f"{top}.py"
        if package.is_file():
            spec = importlib.util.spec_from_file_location(
                top, package, submodule_search_locations=[str(package.parent)]
            )
        elif file.is_file():
            spec = importlib.util.spec_from_file_location(top, file)
        else:
            continue
        loaded = importlib.util.module_from_spec(spec)
        sys.modules[top] = loaded
        try:
            spec.loader.exec_module(loaded)
        except BaseException:
            sys.modules.pop(top, None)
            raise
        return
    raise SceneError(
        _KEY,
        f"cannot import {module!r}: put {top}.py beside the scene file or in the working "
        "directory, or on PYTHONPATH",
    )
