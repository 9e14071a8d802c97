"""Digests of the code a module is built from: its own file and, transitively, the workbench
modules it imports (read from the source, not by importing it).

Two caches are keyed by them: numba's compiled code of workbench's functions and the generated
kernels (:mod:`workbench._cache`), and the blocks of a campaign (its provenance). A digest covers
code, not text: docstrings, comments and formatting are left out (the file's syntax tree without
docstrings is hashed), so an edit of a docstring keys nothing anew, while any change of what
runs does. Imports are followed wherever they stand (module level or inside a function) into
the modules of the package ``workbench`` and of the generated kernels; ``from pkg import sub``
depends on the submodule ``pkg.sub`` alone (not on ``pkg/__init__``) when ``sub`` is one. Other
libraries enter by their version (:func:`environment`).

>>> from workbench._sources import closure, code_digest
>>> "workbench.solver._numerics" in closure("workbench.solver._templates.integration_loop")
True
>>> "workbench.analysis._wolf" in closure("workbench.models.duffing")
False
>>> len(code_digest("workbench.models.duffing"))
16
"""

from __future__ import annotations

import ast
import hashlib
import sys
import sysconfig
import threading
from functools import cache, lru_cache
from pathlib import Path

__all__ = [
    "closure",
    "code_digest",
    "environment",
    "file_digest",
    "module_path",
    "parse",
    "source_digest",
]

_PACKAGE = "workbench"
_PACKAGE_DIR = Path(__file__).resolve().parent
_KERNELS = "workbench_kernels"  # the generated kernels' package (workbench._cache.KERNEL_PACKAGE)
# one import statement: (module, the names of a `from` import or None, relative level)
_Import = tuple[str, tuple[str, ...] | None, int]


def _kernel_directory() -> Path | None:
    """The directory of the generated kernels, once ``solver._compile`` made their package (its
    ``directory``: the package's ``__path__`` is empty, nothing is imported from there)."""
    package = sys.modules.get(_KERNELS)
    return Path(package.directory) if package is not None else None


def _installed(path: Path) -> bool:
    """Whether ``path`` lies in the standard library or an installed distribution (keyed by
    :func:`environment` or by its version, not by its code)."""
    roots = {sysconfig.get_path(k) for k in ("stdlib", "platstdlib", "purelib", "platlib")}
    return any(path.is_relative_to(r) for r in roots if r)


def module_path(name: str) -> Path | None:
    """The source file of module ``name`` of workbench (a package's ``__init__.py``) or of the
    generated kernels (a regular ``.py`` file: never a package), or of any other imported module
    with a ``.py`` file; else None."""
    parts = name.split(".")
    if parts[0] == _KERNELS:
        root = _kernel_directory()
        if root is None or len(parts) != 2:
            return None
        path = root / f"{parts[1]}.py"
        return path if path.is_file() and not path.is_symlink() else None
    if parts[0] == _PACKAGE:
        base = _PACKAGE_DIR.joinpath(*parts[1:])
        if len(parts) > 1 and base.with_suffix(".py").is_file():
            return base.with_suffix(".py")
        init = base / "__init__.py"
        return init if init.is_file() else None
    module = sys.modules.get(name)
    file = getattr(module, "__file__", None)
    return Path(file).resolve() if file and file.endswith(".py") else None


def _followed(name: str) -> bool:
    head = name.split(".")[0]
    return head in (_PACKAGE, _KERNELS)


def _strip_docstrings(tree: ast.AST) -> ast.AST:
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            body = node.body
            if (
                body
                and isinstance(body[0], ast.Expr)
                and isinstance(body[0].value, ast.Constant)
                and isinstance(body[0].value.value, str)
            ):
                node.body = body[1:] or [ast.Pass()]
    return tree


def parse(source: str | bytes, filename: str = "<unknown>") -> ast.Module:
    """``ast.parse`` one source at a time in this process (see :data:`_PARSE`)."""
    with _PARSE:
        return ast.parse(source, filename=filename)


def _analyse(source: str | bytes, filename: str) -> tuple[str, tuple[_Import, ...]]:
    """(SHA-256 of the code, its import statements) of Python source."""
    tree = parse(source, filename)
    imports = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imports.extend((alias.name, None, 0) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            imports.append((node.module or "", tuple(a.name for a in node.names), node.level))
    digest = hashlib.sha256(ast.dump(_strip_docstrings(tree)).encode()).hexdigest()
    return digest, tuple(imports)


#: Python 3.11's parser is not safe to run in two threads at once (``SystemError: AST
#: constructor recursion depth mismatch``, seen when the threads of one dask worker digest the
#: code of their first blocks together): one parse at a time
_PARSE = threading.Lock()


@cache
def _parsed(path: Path, stamp: tuple[int, int]) -> tuple[str, tuple[_Import, ...]]:
    """:func:`_analyse` of one file; ``stamp`` (mtime in ns, size) keys the memo, so an edited
    file is read again."""
    return _analyse(path.read_bytes(), str(path))


def _file(path: Path) -> tuple[str, tuple[_Import, ...]]:
    st = path.stat()
    return _parsed(path, (st.st_mtime_ns, st.st_size))


def file_digest(path: str | Path) -> str:
    """SHA-256 (hex) of the code of one Python file: its syntax tree without docstrings."""
    return _file(Path(path))[0]


def _absolute(module: str, level: int, importer: str, is_package: bool) -> str:
    """The absolute name of a ``from`` import's module (relative imports resolved)."""
    if level == 0:
        return module
    base = importer.split(".") if is_package else importer.split(".")[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([module] if module else []))


def _imports(name: str, imports: tuple[_Import, ...], is_package: bool) -> set[str]:
    """The modules with a source file that module ``name`` imports (``imports``)."""
    found: set[str] = set()
    for module, names, level in imports:
        if names is None:  # import a.b.c
            candidates = [module]
        else:  # from a.b import c, d (c a submodule or a name of a.b)
            base = _absolute(module, level, name, is_package)
            candidates = []
            for n in names:
                sub = f"{base}.{n}"
                candidates.append(sub if n != "*" and module_path(sub) is not None else base)
        found.update(c for c in candidates if module_path(c) is not None)
        for c in candidates:
            if module_path(c) is None and _in_memory(c):
                raise ValueError(
                    f"module {name!r} imports {c!r}, a module built in memory (no source "
                    "file): compiled code keyed by its sources cannot see its code, and a "
                    "cached kernel would outlive an edit of it; write it to a .py file and "
                    "import that"
                )
    return found


def _in_memory(name: str) -> bool:
    """Whether module ``name`` is imported and was built in memory (e.g. ``types.ModuleType``
    put in ``sys.modules``): no file, not built in or frozen, not a namespace package."""
    module = sys.modules.get(name)
    if module is None or getattr(module, "__file__", None) is not None:
        return False
    spec = getattr(module, "__spec__", None)
    if spec is None:
        return True
    return spec.origin in (None, "") and not spec.submodule_search_locations


@cache
def closure(name: str) -> frozenset[str]:
    """Module ``name`` and every workbench (or generated-kernel) module it imports,
    transitively (KeyError if ``name`` has no source file)."""
    if module_path(name) is None:
        raise KeyError(f"module {name!r} has no Python source file to digest")
    seen, todo = set(), [name]
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        seen.add(m)
        path = module_path(m)
        found = _imports(m, _file(path)[1], path.name == "__init__.py")
        todo.extend(n for n in found - seen if _followed(n))
    return frozenset(seen)


@lru_cache(maxsize=1)
def environment() -> str:
    """What else compiled code and results depend on: the versions of Python, numba and NumPy."""
    from importlib.metadata import version

    return f"python {sys.version_info[:3]}; numba {version('numba')}; numpy {version('numpy')}"


def code_digest(*modules: str) -> str:
    """16-hex digest of the code of ``modules`` and all they import (:func:`closure`), with
    :func:`environment`: equal digests mean equal code, whatever the docstrings and comments."""
    names = sorted(set().union(*(closure(m) for m in modules)))
    h = hashlib.sha256(environment().encode())
    for m in names:
        h.update(f"\n{m} {file_digest(module_path(m))}".encode())
    return h.hexdigest()[:16]


def source_digest(source: str, name: str) -> str:
    """16-hex digest of the code of ``source`` (to become module ``name``) and of every module
    with a source file it imports (:func:`code_digest`: a model's hooks module too, inside the
    package or not), with :func:`environment`."""
    digest, imports = _analyse(source, name)
    h = hashlib.sha256(f"{environment()}\n{digest}".encode())
    for m in sorted(_imports(name, imports, False)):
        if not _followed(m) and _installed(module_path(m)):
            continue
        # a generated module: the digest in its name (its text is generated, not read back)
        digest = m.rsplit("_", 1)[-1] if m.startswith(f"{_KERNELS}.") else code_digest(m)
        h.update(f"\n{m} {digest}".encode())
    return h.hexdigest()[:16]
