"""The numba cache: workbench's compiled functions go to directories keyed by the digest of the
code they are built from, every other library's stay where numba puts them, and the process
environment is not touched. An edit of a docstring, of the analysis layer or of another model
recompiles nothing; an edit of a model's code recompiles that model (issue 28)."""

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import workbench
from workbench._sources import closure, file_digest

OTHER = """
from numba import njit

@njit(cache=True)
def plus_one(x):
    return x + 1
"""

SCRIPT = """
import os
import numpy as np
import workbench
from workbench._cache import module_digest
from workbench.solver._templates.placeholder_hooks import rhs
import other_lib

assert other_lib.plus_one(1) == 2
rhs(0.0, np.ones(2), np.zeros(0), np.zeros(0, np.int64), np.zeros(0), np.zeros(1), np.empty(2))
hooks = "workbench.solver._templates.placeholder_hooks"
print(os.environ.get("NUMBA_CACHE_DIR"), module_digest(hooks))
"""


def test_only_workbench_functions_use_its_cache(tmp_path):
    (tmp_path / "other_lib.py").write_text(textwrap.dedent(OTHER))
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(WORKBENCH_CACHE_DIR=str(tmp_path / "wb"), PYTHONPATH=str(tmp_path))
    out = subprocess.run(
        [sys.executable, "-c", SCRIPT],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    assert out[0] == "None"  # NUMBA_CACHE_DIR was not set for the process
    ours = sorted(p.name for p in (tmp_path / "wb" / "numba" / out[1]).rglob("*.nbi"))
    assert ours and all(name.startswith("placeholder_hooks.rhs-") for name in ours)
    theirs = sorted(p.name for p in (tmp_path / "__pycache__").glob("*.nbi"))
    assert theirs and all(name.startswith("other_lib.plus_one-") for name in theirs)


def test_a_copy_of_the_package_elsewhere_loads_what_another_copy_compiled(tmp_path):
    """The cache is keyed by the code's digest and the package's name, not by where its files
    lie (numba's own folder name hashes that path): a second copy of the same code, elsewhere,
    compiles nothing (issue 40: a copy's first nine-bar run spent 20 s of CPU compiling the
    mechanism's records anew, with no notice)."""
    package = Path(workbench.__file__).parent
    for copy in ("a", "b"):
        ignore = shutil.ignore_patterns("__pycache__")
        shutil.copytree(package, tmp_path / copy / "workbench", ignore=ignore)
    (tmp_path / "other_lib.py").write_text(textwrap.dedent(OTHER))

    def saved(copy: str) -> list[str]:
        """The cache files numba wrote for a process of ``copy`` (NUMBA_DEBUG_CACHE)."""
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
        env.update(
            WORKBENCH_CACHE_DIR=str(tmp_path / "cache"),
            PYTHONPATH=f"{tmp_path / copy}{os.pathsep}{tmp_path}",
            NUMBA_DEBUG_CACHE="1",
        )
        out = subprocess.run(
            [sys.executable, "-c", SCRIPT],
            cwd=tmp_path / copy,
            env=env,
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        return [line for line in out.splitlines() if line.startswith("[cache] data saved")]

    first = saved("a")
    assert any("placeholder_hooks.rhs-" in line for line in first), first
    assert saved("b") == []


def test_a_digest_covers_code_not_docstrings_comments_or_layout(tmp_path):
    code = 'def f(x):\n    """Twice x (m)."""\n    return 2 * x  # doubled\n'
    same = '"""A module."""\n\n\ndef f(x):\n    """Twice x, in m."""\n\n    return 2*x\n'
    other = 'def f(x):\n    """Twice x (m)."""\n    return 3 * x\n'
    digests = []
    for i, text in enumerate((code, same, other)):
        (tmp_path / f"m{i}.py").write_text(text)
        digests.append(file_digest(tmp_path / f"m{i}.py"))
    assert digests[0] == digests[1] != digests[2]


def test_a_models_code_closure_holds_what_it_is_built_from_and_nothing_else():
    duffing, ninebar = (
        closure("workbench.models.duffing"),
        closure("workbench.models.ninebar._model"),
    )
    assert {"workbench.models._base", "workbench.solver._problem"} <= duffing
    assert {"workbench.models.ninebar._dynamics", "workbench.models.friction"} <= ninebar
    for layer in ("analysis", "plot", "study", "campaign", "scene", "run", "cli"):
        assert not any(m.startswith(f"workbench.{layer}") for m in duffing | ninebar), layer
    assert not any(m.startswith("workbench.models.ninebar") for m in duffing)
    assert "workbench.models.duffing" not in ninebar
    # a kernel's templates are read as text: the results' digest names them
    kernel = closure("workbench.solver._templates.integration_loop")
    assert {"workbench.solver._numerics", "workbench.solver._templates.explicit_steps"} <= kernel


EDIT = """
import sys
import workbench
from workbench.run import prepare
from workbench.solver._compile import kernel_for

hooks = prepare({"model": {"name": "duffing"}, "run": {"cycles": 1}}).problem.hooks
print(bool(kernel_for(hooks).advance._cache._cache_file._load_index()))
if sys.argv[1] == "run":
    workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 1}})
"""


@pytest.mark.slow
def test_only_an_edit_of_the_code_a_kernel_is_built_from_recompiles_it(tmp_path):
    """A copy of the package: compile Duffing's kernel, then edit a docstring of the model, the
    analysis layer and another model (the kernel stays cached), then Duffing's code (it is
    not). Measured on the copy, whose cache is its own."""
    package = Path(workbench.__file__).parent
    shutil.copytree(package, tmp_path / "workbench", ignore=shutil.ignore_patterns("__pycache__"))
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(WORKBENCH_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=str(tmp_path))

    def cached(action: str = "check") -> bool:
        out = subprocess.run(
            [sys.executable, "-c", EDIT, action],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
        return out.stdout.split()[0] == "True"

    def edit(relative: str, old: str | None = None, new: str = "") -> None:
        """Replace ``old`` by ``new`` once, or append a line of code."""
        path = tmp_path / "workbench" / relative
        text = path.read_text()
        assert old is None or old in text, (relative, old)
        path.write_text(text + "\nX_EDITED = 1\n" if old is None else text.replace(old, new, 1))

    assert not cached("run")  # compiled by this call
    assert cached()
    edit("models/duffing.py", '"""', '"""An edited docstring. ')
    edit("analysis/_zero_one.py")
    edit("models/lorenz.py")
    assert cached()
    edit("models/duffing.py")
    assert not cached()


@pytest.mark.parametrize("hooks", ["workbench.models.bouncing_ball", "workbench.models.duffing"])
def test_generated_code_imports_no_template(hooks):
    """Every tagged import of a template points at the model or a generated module in the
    generated code, however a formatter wrapped it (a wrapped import of the placeholder hooks
    once left the tangent system and the copies without the model's events)."""
    import ast

    from workbench.solver._compile import _kernel_parts, copies_for, jacobian_for, tangent_for

    tangent = tangent_for(hooks)
    modules = [
        *_kernel_parts(hooks).values(),
        jacobian_for(hooks),
        tangent,
        copies_for(hooks),
        *_kernel_parts(tangent.__name__).values(),
    ]
    for module in modules:
        tree = ast.parse(Path(module.__file__).read_text())
        imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
        assert not any(m.startswith("workbench.solver._templates") for m in imported), (
            module.__name__,
            sorted(imported),
        )
    assert hooks in {
        n.module
        for n in ast.walk(ast.parse(Path(tangent.__file__).read_text()))
        if isinstance(n, ast.ImportFrom)
    }


def test_a_kernel_importing_an_in_memory_module_is_refused():
    """A hooks module built in memory has no source to digest: the kernel's key would miss an
    edit of the model it imports (benchmarks/ninebar_speed.py ran stale machine code so).
    Refused, naming the module."""
    import types

    from workbench._sources import source_digest

    sys.modules["wb_in_memory_hooks"] = types.ModuleType("wb_in_memory_hooks")
    try:
        with pytest.raises(ValueError, match="'wb_in_memory_hooks', a module built in memory"):
            source_digest("from wb_in_memory_hooks import rhs\n", "kernel_x")
        assert source_digest("import math\n", "kernel_x")  # built in: fine
    finally:
        del sys.modules["wb_in_memory_hooks"]
