"""The numba cache: workbench's compiled functions go to its digest-keyed directory, every other
library's stay where numba puts them, and the process environment is not touched."""

import os
import subprocess
import sys
import textwrap

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
from workbench._cache import package_digest
from workbench.solver._hooks_template import rhs
import other_lib

assert other_lib.plus_one(1) == 2
rhs(0.0, np.ones(2), np.zeros(0), np.zeros(0, np.int64), np.zeros(0), np.zeros(1), np.empty(2))
print(os.environ.get("NUMBA_CACHE_DIR"), package_digest())
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
    assert ours and all(name.startswith("_hooks_template.rhs-") for name in ours)
    theirs = sorted(p.name for p in (tmp_path / "__pycache__").glob("*.nbi"))
    assert theirs and all(name.startswith("other_lib.plus_one-") for name in theirs)
