"""The lean right-hand sides against the record-time evaluation (the reference formulation).

The solver's hook ``rhs`` of each mechanism computes only what the integration reads; the
record-time ``evaluate`` assembles the full system (every Jacobian column, every body) and is
the formulation the models had before the lean hooks. At every record of a run, in every effect
combination, both must give the same dy/dt, return code, LuGre decay rate and implicit-stage
bristle solution to rounding; and integrated by the same solver over a horizon where the motion
is regular, the same events.
"""

from __future__ import annotations

import importlib
import math
import sys
import types

import numpy as np
import pytest

import workbench
from workbench.models._layout import layout
from workbench.models._mechanism_layouts import JOINT
from workbench.run import prepare
from workbench.solver import EVENT_INSIDE_STEP, integrate

SCENE = "studies/ninebar.toml"
RTOL = 1e-12  # of each rate's largest magnitude over the run


def lean_against_reference(scene, *, method: str = "dop853", hg: float = 1e-5) -> float:
    """Integrate ``scene``, then at every record compare the lean ``rhs`` with
    ``rhs_reference`` (as recorded, with the contact onsets unlocated, and in an implicit ARK548
    stage with h gamma = ``hg`` s); returns the largest difference relative to each rate's
    largest magnitude over the records, after asserting equal codes, decay rates and bristles."""
    prepared = prepare(scene)
    problem, t_rec = prepared.problem, prepared.times
    run = integrate(problem, t_rec, method=method, rtol=1e-6, atol=1e-6)
    hooks = importlib.import_module(problem.hooks)
    lean, ref = [], []
    codes = set()
    for i in range(run.t.size):
        for aux in (run.AUX[i], np.zeros_like(run.AUX[i])):
            for stage_hg in (0.0, hg) if problem.stiff_states.size else (0.0,):
                out = []
                for f in (hooks.rhs, hooks.rhs_reference):
                    y = run.Y[i].copy()
                    work = np.zeros(problem.work_size)
                    work[problem.implicit_slot] = stage_hg
                    dydt = np.full(y.size, np.nan)
                    code = f(run.t[i], y, problem.p, problem.ip, aux.copy(), work, dydt)
                    out.append((code, dydt, y, work[problem.stiff_slots]))
                (c1, d1, y1, a1), (c2, d2, y2, a2) = out
                assert c1 == c2, (run.t[i], c1, c2)
                codes.add(c1)
                if c1 in (0, EVENT_INSIDE_STEP):
                    lean.append(np.concatenate([d1, y1, a1]))
                    ref.append(np.concatenate([d2, y2, a2]))
    assert 0 in codes
    lean, ref = np.array(lean), np.array(ref)
    scale = np.abs(ref).max(axis=0)
    scale[scale == 0.0] = 1.0
    return float((np.abs(lean - ref) / scale).max())


@pytest.mark.parametrize("gravity", [True, False], ids=["gravity", "no_gravity"])
@pytest.mark.parametrize("friction", ["none", "coulomb", "lugre"])
@pytest.mark.parametrize("joints", [["A"], ["B"], ["A", "B"]], ids=["A", "B", "AB"])
def test_lean_rhs_equals_the_reference(joints, friction, gravity):
    """0.2 s from rest at the default omega (contacts, impacts, sliding; 201 records, each also
    with its onsets unlocated and as an implicit stage), energy quadratures on. Measured: at
    most 2.0e-15 of each rate's range (B, no friction, gravity)."""
    base = workbench.load_scene(SCENE)
    scene = base.replace(
        effects={"clearance": joints, "friction": friction, "gravity": gravity},
        run={"duration": 0.2, "transient": 0.0},
        record={"dt": 1e-3, "variables": ["clearance_x", "driver_work", "dissipated_energy"]},
    )
    assert lean_against_reference(scene) < RTOL


def _reference_hooks(monkeypatch, model_module: str) -> str:
    """A hooks module whose ``rhs`` is the model's ``rhs_reference``; returns its name."""
    dyn = importlib.import_module(model_module)
    name = f"reference_hooks_{model_module.replace('.', '_')}"
    mod = types.ModuleType(name)
    mod.rhs = dyn.rhs_reference
    mod.event_values = dyn.event_values
    mod.apply_event = dyn.apply_event
    monkeypatch.setitem(sys.modules, name, mod)
    return name


def same_run_as_reference(monkeypatch, scene, *, rtol: float, early: float) -> tuple[float, float]:
    """Integrate ``scene`` with ``scipy:DOP853`` once with the lean hooks and once with the
    reference; assert equal event counts; return the largest record difference of the state
    relative to its range up to time ``early`` (s) and over the whole run."""
    prepared = prepare(scene)
    problem, t_rec = prepared.problem, prepared.times
    runs = []
    for hooks in (problem.hooks, _reference_hooks(monkeypatch, problem.hooks)):
        problem.hooks = hooks
        runs.append(integrate(problem, t_rec, method="scipy:DOP853", rtol=rtol, atol=rtol))
    lean, ref = runs
    assert lean.stats["events"] == ref.stats["events"] > 0
    diff = (np.abs(lean.Y - ref.Y) / np.ptp(ref.Y, axis=0)).max(axis=1)
    return float(diff[t_rec <= early].max()), float(diff.max())


@pytest.mark.chaotic
def test_same_events_as_the_reference_over_a_regular_horizon(monkeypatch):
    """At omega = pi the motion stays regular (see test_ninebar): over 0.5 s at rtol 1e-10 the
    lean and the reference right-hand sides give the same 88 events. Their rounding-level
    difference grows from the first impacts on, as between any two correct solvers (test_ninebar
    bounds that by 1e-3 c): measured 1.4e-7 of each state's range over the first 20 ms,
    1.7e-4 over the whole run."""
    base = workbench.load_scene(SCENE)
    scene = base.replace(
        parameters={**base.parameters, "omega": math.pi},
        run={"duration": 0.5, "transient": 0.0},
        record={"dt": 1e-3, "variables": ["clearance_x"]},
    )
    early, whole = same_run_as_reference(monkeypatch, scene, rtol=1e-10, early=0.02)
    assert early < 1e-6
    assert whole < 1e-3


def test_layout_offsets_follow_the_declared_sizes():
    lay = layout("Demo", [("a", 2), ("b", 0), ("c", 3)])
    assert (lay.a, lay.b, lay.c, lay.size) == (0, 2, 2, 5)
    assert lay.block("c") == slice(2, 5)
    np.testing.assert_array_equal(lay.pack({"c": [1, 2, 3]}, fill=-1), [-1, -1, 1, 2, 3])
    with pytest.raises(ValueError, match="Demo.c has 3 entries"):
        lay.pack({"c": [1.0]})
    with pytest.raises(KeyError):
        lay.pack({"d": 1.0})
    with pytest.raises(ValueError, match="distinct"):
        layout("Bad", [("a", 1), ("a", 1)])
    # the shared per-joint block lies whole inside each model's parameter array
    from workbench.models.ninebar._dynamics import P

    assert P.friction - P.joint == 2 * JOINT.size
