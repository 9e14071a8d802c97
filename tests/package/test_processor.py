"""Which processor computed a result (issue 36): every run records the processor and the target
numba compiled its kernels for, since another instruction set rounds differently and a chaotic
run then follows another trajectory (its numbers agree within their errors, not in digits)."""

import os
import subprocess
import sys

import llvmlite.binding as ll

import workbench
from workbench._processor import compile_target, processor_attrs

SCENE = {"model": {"name": "duffing"}, "run": {"cycles": 1}}


def test_a_run_records_its_processor_and_compile_target():
    ds = workbench.simulate(SCENE)
    attrs = processor_attrs()
    assert {k: ds.attrs[k] for k in attrs} == attrs
    target, features = compile_target()
    assert target.split()[0] == ll.get_default_triple()
    expected = os.environ.get("NUMBA_CPU_NAME") or ll.get_host_cpu_name()
    assert target.split()[-1] == expected
    assert len(features) == 12 and int(features, 16) >= 0
    assert ds.attrs["processor"]


def test_a_generic_target_is_recorded_as_such():
    """``NUMBA_CPU_NAME=generic`` (numba's own setting) compiles for the baseline CPU of the
    architecture, with no optional features: the record says so."""
    code = "from workbench._processor import compile_target; print(*compile_target())"
    env = {**os.environ, "NUMBA_CPU_NAME": "generic"}
    env.pop("NUMBA_CPU_FEATURES", None)
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    target, features = done.stdout.split()[-2:]
    assert target == "generic"
    host = subprocess.run(
        [sys.executable, "-c", code],
        env={k: v for k, v in os.environ.items() if not k.startswith("NUMBA_CPU")},
        capture_output=True,
        text=True,
        check=True,
    )
    assert host.stdout.split()[-2] == ll.get_host_cpu_name()
    assert host.stdout.split()[-1] != features  # the host's features are not the baseline's
