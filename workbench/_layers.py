"""The layers of the package, lowest first: each module imports only modules of its own layer or
of a layer before it (``tests/package/test_layers.py`` checks every import, at module level or
inside a
function, and that the imports form no cycle).

A module belongs to the layer of the longest prefix below that names it. The package's own
``__init__`` (the public facade, ``import workbench``) sits above every feature and below the
command line (``workbench.cli``), which nothing imports.
"""

from __future__ import annotations

__all__ = ["LAYERS", "layer_of"]

LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    (
        "base",
        (
            "workbench._attributes",
            "workbench._cache",
            "workbench._checks",
            "workbench._errors",
            "workbench._layers",
            "workbench._processor",
            "workbench._progress",
            "workbench._sources",
            "workbench._version",
            "workbench._warnings",
        ),
    ),
    ("solver", ("workbench.solver",)),  # its protocol (Problem, RunResult, Status), integrators
    ("models", ("workbench.models",)),  # build Problems
    ("scene", ("workbench.scene",)),  # validated against the models
    ("run", ("workbench.run",)),  # scene -> problem -> result -> dataset
    ("archive", ("workbench.archive",)),
    ("precision", ("workbench.precision",)),  # workbench.accuracy, recommend
    ("analysis", ("workbench.analysis",)),
    ("plot", ("workbench.plot",)),
    ("campaign", ("workbench.campaign",)),
    ("continuation", ("workbench.continuation",)),  # continued sweeps, periodic orbits
    ("verification", ("workbench.verification",)),  # workbench.verify
    ("study", ("workbench.study",)),
    ("cli", ("workbench.cli", "workbench.cli._exit_codes", "workbench.cli._console")),
)


def layer_of(module: str) -> int:
    """Index in :data:`LAYERS` of a workbench module (dotted name)."""
    if module == "workbench":
        return len(LAYERS) - 2
    best, rank = -1, None
    for i, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best:
                best, rank = len(prefix), i
    if rank is None:
        raise KeyError(f"module {module!r} is in no layer of workbench._layers.LAYERS; add it")
    return rank
