"""What a person meets first on the command line (issue 40, item 10): a help that starts at
once."""

import subprocess
import sys
from pathlib import Path

import pytest

import workbench

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("numba", "xarray", "dask", "matplotlib", "scipy", "pandas", "distributed", "netCDF4")


def test_help_imports_no_numerical_library():
    """``workbench --help`` and every ``workbench COMMAND --help`` parse with none of numba,
    xarray, dask, matplotlib (nor scipy, pandas) imported: counted in a fresh process, not
    timed."""
    code = (
        "import sys\n"
        "from workbench.cli import build_parser, main\n"
        "commands = [None] + list(next(a for a in build_parser()._actions"
        " if a.dest == 'command').choices)\n"
        "for command in commands:\n"
        "    try:\n"
        "        main(['--help'] if command is None else [command, '--help'])\n"
        "    except SystemExit:\n"
        "        pass\n"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules), file=sys.stderr)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert out.stderr.strip().splitlines()[-1] == "[]", out.stderr[-2000:]
    assert "usage: workbench verify" in out.stdout and "usage: workbench [-h]" in out.stdout


def test_import_workbench_loads_its_names_on_first_use():
    """The public names still come with ``import workbench`` (loaded when first used)."""
    code = (
        "import sys, workbench\n"
        "before = 'numba' in sys.modules\n"
        "from workbench import simulate, Status\n"
        "print(before, 'numba' in sys.modules, simulate.__module__, Status.OK.label)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert out.stdout.split() == ["False", "True", "workbench.run._simulate", "ok"]
    assert sorted(set(workbench.__all__) - set(dir(workbench))) == []
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        workbench.nope  # noqa: B018
