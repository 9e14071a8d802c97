"""The processor a run's compiled code was built for, recorded with its results.

numba compiles the kernels for the host processor (its LLVM CPU name and instruction-set
features) unless told otherwise (``NUMBA_CPU_NAME``, ``NUMBA_CPU_FEATURES``). Processors with
other features round some operations differently (fused multiply-add, vector widths, the math
library's variant), and a chaotic run turns a difference in the last digit into another
trajectory within a few periods: results agree within their errors across processors, and
bit for bit only for the same code on the same target. So every run records the target
(``compile_target``: the LLVM triple and CPU name; ``compile_features``: a digest of the
feature string) and the processor's model (``processor``). ``NUMBA_CPU_NAME=generic`` compiles
for a fixed, baseline target that every x86-64 node shares (docs/cluster.md).
"""

from __future__ import annotations

import hashlib
import platform
from functools import cache
from pathlib import Path

__all__ = ["PROCESSOR_ATTRS", "compile_target", "processor_attrs"]

# the global attributes of a result that name what computed it (:func:`processor_attrs`)
PROCESSOR_ATTRS = ("processor", "compile_target", "compile_features")


@cache
def compile_target() -> tuple[str, str]:
    """The target numba compiles this process's kernels for: ``("<triple> <cpu name>", "<12-hex
    digest of the feature string>")``, as numba keys its cache (``codegen.magic_tuple()``)."""
    from numba.core.registry import cpu_target

    triple, name, features = cpu_target.target_context.codegen().magic_tuple()
    digest = hashlib.sha256(features.encode()).hexdigest()[:12]
    return f"{triple} {name}", digest


@cache
def processor_model() -> str:
    """The processor's model name (``/proc/cpuinfo``'s ``model name``, else
    :func:`platform.processor`, else the machine type)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def processor_attrs() -> dict[str, str]:
    """Global attributes that say which processor and compile target computed a result."""
    target, features = compile_target()
    return {
        "processor": processor_model(),
        "compile_target": target,
        "compile_features": features,
    }
