"""The LuGre law on a single bristle, where the answers are known (issue 29).

The compiled law of :mod:`workbench.models.friction` (the functions the mechanisms inline) drives
a block on a surface with a constant normal force F_n, integrated by scipy's Radau IIA (an
integrator independent of the project's): pulled at a constant velocity it reaches the steady
state of the law, mu_ss = g(v) sign(v) + s2 v; below break-away it rests on a spring of stiffness
s0 F_n with the damping (s1 + s2) F_n; a passive parameter set never returns energy. And a
default LuGre run of the nine-bar keeps its friction coefficient within the law's envelope,
where the paper's constant damping leaves it.
"""

import itertools
import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import workbench
from workbench.models.friction import (
    lugre_coefficient,
    lugre_damping,
    lugre_decay,
    lugre_passive_damping,
    lugre_passive_damping_velocity,
    stribeck,
)

# the paper's normalised parameters (docs/ninebar-parameters.md)
MU_K, MU_S, S0, S2, V_S, GAMMA = 0.05, 0.15, 1e5, 0.4, 1e-3, 2.0
PAPER_S1 = 316.2  # s m-1, constant: the paper's value
DEFAULT = {"s1": PAPER_S1, "v_d": 1e-3}  # the package's default: Olsson's fading damping
PASSIVE_CONSTANT = {"s1": lugre_passive_damping(MU_K, MU_S, S2), "v_d": 0.0}
PAPER = {"s1": PAPER_S1, "v_d": 0.0}


def mu_of(v, z, law):
    """Friction coefficient and bristle rate (m s-1) of the law at sliding velocity v (m s-1)
    and deflection z (m)."""
    zdot = v - lugre_decay(v, S0, MU_K, MU_S, V_S, GAMMA) * z
    s1 = lugre_damping(v, law["s1"], law["v_d"])
    return lugre_coefficient(v, z, zdot, S0, s1, S2), zdot


def test_passive_damping_bounds():
    """Barabanov & Ortega's bound for a constant damping is s2 mu_k / (mu_s - mu_k), and the
    fading damping of the defaults lies inside its own bound 4 sqrt(2 e) mu_k / s1."""
    assert lugre_passive_damping(MU_K, MU_S, S2) == pytest.approx(0.2, rel=1e-12)
    assert lugre_passive_damping(0.1, 0.1, S2) == math.inf
    v_max = lugre_passive_damping_velocity(MU_K, PAPER_S1)
    assert v_max == pytest.approx(4 * math.sqrt(2 * math.e) * 0.05 / 316.2, rel=1e-12)
    assert DEFAULT["v_d"] < v_max < 1.5e-3
    assert lugre_damping(0.0, PAPER_S1, 1e-3) == PAPER_S1
    assert lugre_damping(1e-3, PAPER_S1, 1e-3) == pytest.approx(PAPER_S1 / math.e, rel=1e-14)
    assert lugre_damping(0.08, PAPER_S1, 0.0) == PAPER_S1


@pytest.mark.parametrize("law", [DEFAULT, PASSIVE_CONSTANT, PAPER], ids=["default", "B&O", "paper"])
@pytest.mark.parametrize("v", [-0.3, -2e-3, 5e-4, 1e-3, 4e-3, 0.08, 1.0])
def test_steady_sliding_at_constant_velocity(law, v):
    """Pulled at a constant velocity v from z = 0, the bristle relaxes to g(v) sign(v) / s0 and
    the coefficient to mu_ss = g(v) sign(v) + s2 v, whatever the damping (z_dot -> 0); above
    the Stribeck range that is mu_k + s2 v."""
    rate = lugre_decay(v, S0, MU_K, MU_S, V_S, GAMMA)
    sol = solve_ivp(
        lambda t, y: [mu_of(v, y[0], law)[1]], (0.0, 40.0 / rate), [0.0], method="Radau",
        rtol=1e-12, atol=1e-18,
    )  # fmt: skip
    mu, zdot = mu_of(v, sol.y[0, -1], law)
    g = stribeck(v, MU_K, MU_S, V_S, GAMMA)
    assert g == pytest.approx(MU_K + (MU_S - MU_K) * math.exp(-((v / V_S) ** 2)), rel=1e-14)
    assert abs(zdot) < 1e-12 * abs(v)
    assert mu == pytest.approx(g * math.copysign(1.0, v) + S2 * v, rel=1e-9)
    if abs(v) >= 0.08:
        assert mu == pytest.approx(math.copysign(MU_K, v) + S2 * v, rel=1e-9)


def test_block_pulled_through_a_spring_slides_at_mu_k_plus_s2_v():
    """A 1-kg block on a surface (F_n = 9.81 N) pulled through a stiff spring whose end moves
    at 0.05 m/s (beyond the Stribeck range: steady sliding is stable, its oscillation decaying
    at s2 F_n / (2 m) = 2 s-1) settles at that speed, the spring holding mu_ss F_n =
    (mu_k + s2 v) F_n."""
    m, fn, k, vp, end = 1.0, 9.81, 1e4, 0.05, 12.0

    def rhs(t, y):
        x, v, z = y
        mu, zdot = mu_of(v, z, DEFAULT)
        return [v, (k * (vp * t - x) - mu * fn) / m, zdot]

    sol = solve_ivp(rhs, (0.0, end), [0.0, 0.0, 0.0], method="Radau", rtol=1e-10, atol=1e-13)
    x, v, z = sol.y[:, -1]
    assert v == pytest.approx(vp, rel=1e-6)
    assert k * (vp * end - x) / fn == pytest.approx(MU_K + S2 * vp, rel=1e-6)


@pytest.mark.parametrize(
    ("law", "fn"), [(DEFAULT, 1.0), (PASSIVE_CONSTANT, 10.0)], ids=["default", "B&O"]
)
def test_presliding_is_a_spring_of_stiffness_s0_fn(law, fn):
    """Below break-away a block of mass m rests on the bristles as on a spring of stiffness
    s0 F_n with the viscous damping (s1 + s2) F_n: launched at 1e-6 m/s (amplitude ~1e-9 m, far
    below the sliding deflection mu_s / s0 = 1.5e-6 m) it oscillates at omega_n sqrt(1 - zeta^2)
    with omega_n = sqrt(s0 F_n / m) and decays at zeta omega_n, zeta = (s1 + s2) F_n /
    (2 sqrt(s0 F_n m)) (the default's s1 = 316.2 s m-1 gives zeta = 1/2 at F_n = 1 N, as the
    force-form example of Canudas de Wit et al. 1995 with m = 1 kg)."""
    m, v0 = 1.0, 1e-6
    k = S0 * fn
    wn = math.sqrt(k / m)
    zeta = (law["s1"] + S2) * fn / (2 * math.sqrt(k * m))
    wd = wn * math.sqrt(1 - zeta**2)

    def rhs(t, y):
        x, v, z = y
        mu, zdot = mu_of(v, z, law)
        return [v, -mu * fn / m, zdot]

    t = np.linspace(0.0, 3 * 2 * math.pi / wd, 3001)
    sol = solve_ivp(rhs, t[[0, -1]], [0.0, v0, 0.0], method="Radau", t_eval=t, rtol=1e-11,
                    atol=1e-17)  # fmt: skip
    x, v, z = sol.y
    # the bristles carry the motion: the slip x - z is of the order s0 |x| / g ~ 1e-3 of x
    assert np.max(np.abs(x - z)) < 3e-3 * np.max(np.abs(x))
    # the linear oscillator from the same start: x = v0 / wd exp(-zeta wn t) sin(wd t)
    linear = v0 / wd * np.exp(-zeta * wn * t) * np.sin(wd * t)
    assert np.max(np.abs(x - linear)) < 1e-2 * np.max(np.abs(linear))
    # the restoring force without its viscous part, against x: the spring's stiffness
    force = [mu_of(vv, zz, law)[0] * fn for vv, zz in zip(v, z, strict=True)]
    viscous = [(lugre_damping(vv, law["s1"], law["v_d"]) + S2) * fn * vv for vv in v]
    stiffness = np.polyfit(x, np.subtract(force, viscous), 1)[0]
    assert stiffness == pytest.approx(k, rel=3e-3)


def _sine(amplitude, period=1.0):
    """Sliding velocity amplitude sin(2 pi t / period) (m s-1) over two periods, and the
    pieces to integrate it in (s)."""
    return (lambda t: amplitude * math.sin(2 * math.pi * t / period)), [0.0, 2 * period]


def _jolts(creep=1e-4, fast=0.05, rise=1e-6):
    """Stick, then a jolt: creep at ``creep`` m/s for 0.2 s (the bristles load to about mu_s /
    s0), rise to ``fast`` m/s within ``rise`` s (far quicker than the bristles relax, 1e-5 s at
    0.05 m/s), slide 0.01 s, and the same back in the other direction."""
    edges = [0.0, 0.2, 0.2 + rise, 0.21, 0.41, 0.41 + rise, 0.42]

    def v(t):
        sign = 1.0 if t < 0.21 else -1.0
        start = edges[1] if t < 0.21 else edges[4]
        s = min(max((t - start) / rise, 0.0), 1.0)
        return sign * (creep + (fast - creep) * 0.5 * (1.0 - math.cos(math.pi * s)))

    return v, edges


def _forced_cycle(law, velocity, pieces):
    """A bristle under the prescribed sliding velocity ``velocity(t)`` (m s-1) from z = 0,
    integrated piece by piece between the times ``pieces`` (s): times (s), z (m), and the work
    of the friction per unit normal force W = int mu v dt (m; F_t = -mu F_n, so mu v F_n is
    the power it takes)."""

    def rhs(t, y):
        v = velocity(t)
        mu, zdot = mu_of(v, y[0], law)
        return [zdot, mu * v]

    ts, zs, ws, y0 = [], [], [], [0.0, 0.0]
    for a, b in itertools.pairwise(pieces):
        t = np.linspace(a, b, 4001)
        sol = solve_ivp(rhs, (a, b), y0, method="Radau", t_eval=t, rtol=1e-11,
                        atol=[1e-18, 1e-16], max_step=(b - a) / 500)  # fmt: skip
        ts.append(t)
        zs.append(sol.y[0])
        ws.append(sol.y[1])
        y0 = sol.y[:, -1]
    return np.concatenate(ts), np.concatenate(zs), np.concatenate(ws)


FORCING = {
    "sine 2e-3 m/s": _sine(2e-3),  # the speeds where the default's fading damping acts most
    "sine 0.05 m/s": _sine(0.05),
    "stick and jolts": _jolts(),
}


@pytest.mark.parametrize("forcing", list(FORCING))
@pytest.mark.parametrize("law", [DEFAULT, PASSIVE_CONSTANT], ids=["default", "B&O"])
def test_passive_law_never_returns_energy(law, forcing):
    """Over a forced cycle the energy the law has dissipated, D = W - s0 z^2 / 2 (work taken
    minus what the bristles store; per unit normal force, m), never decreases."""
    t, z, work = _forced_cycle(law, *FORCING[forcing])
    dissipated = work - 0.5 * S0 * z**2
    assert np.min(np.diff(dissipated)) > -1e-9 * np.max(np.abs(work))
    assert dissipated[-1] > 0.0


def test_paper_damping_returns_energy():
    """The paper's constant s1 = 316 s m-1 is not passive: at the jolt from sticking to 0.05 m/s
    the bristles, loaded to about mu_s / s0, relax at z_dot ~ (1 - mu_s / mu_k) v = -2 v, and the
    damping term s1 z_dot ~ -30 pushes the block forward: the friction's work W itself falls,
    by some 100 times the most its bristles can store (mu_s^2 / (2 s0)): energy is created."""
    t, z, work = _forced_cycle(PAPER, *FORCING["stick and jolts"])
    dissipated = work - 0.5 * S0 * z**2
    stored_at_most = MU_S**2 / (2 * S0)
    assert np.max(np.maximum.accumulate(work) - work) > 50 * stored_at_most
    assert np.max(np.maximum.accumulate(dissipated) - dissipated) > 50 * stored_at_most


def test_power_form_is_nonnegative_on_the_invariant_set():
    """The passivity argument of :mod:`workbench.models.friction`: mu v - s0 z z_dot >= 0 for
    every |z| <= mu_s / s0 and sliding velocity, for the default and for the constant damping
    at Barabanov & Ortega's bound; negative somewhere for the paper's constant damping."""
    v = np.concatenate([-np.logspace(-6, 0, 300), np.logspace(-6, 0, 300)])
    z = np.linspace(-MU_S / S0, MU_S / S0, 201)

    def worst(law):
        return min(
            mu_of(vv, zz, law)[0] * vv - S0 * zz * mu_of(vv, zz, law)[1] for vv in v for zz in z
        )

    assert worst(DEFAULT) >= -1e-15
    assert worst(PASSIVE_CONSTANT) >= -1e-15
    assert worst(PAPER) < -1e-3


def _lugre_run(**parameters):
    base = workbench.load_scene("studies/friction_models/lugre.toml")
    scene = base.replace(
        parameters={**base.parameters, **parameters},
        solver={**base.solver, "method": "ark548"},
        run={"duration": 0.4, "transient": 0.0},
        record={"dt": 1e-4, "variables": ["contact_force"]},
    )
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = workbench.simulate(scene)
    return ds, [w for w in caught if issubclass(w.category, workbench.ModelWarning)]


def test_default_lugre_run_stays_within_its_law():
    """The first 0.4 s of the paper's Sec. 4.2 LuGre case (impacts and sliding at both joints):
    with the default damping no time beyond the law's envelope and no warning; the records
    carry the diagnostics with units. With the paper's constant damping the coefficient leaves
    the envelope for milliseconds, and the run warns, naming the cause."""
    ds, caught = _lugre_run()
    for name, units in (
        ("friction_ratio", "1"),
        ("time_above_static_friction", "s"),
        ("time_beyond_friction_law", "s"),
    ):
        assert ds[name].attrs["units"] == units and ds[name].dims == ("time", "joint")
    assert float(ds.time_beyond_friction_law[-1].max()) == 0.0
    assert float(ds.friction_ratio.max()) < 2 * MU_S
    assert not caught
    paper, caught = _lugre_run(lugre_damping_velocity=0.0)
    assert float(paper.time_beyond_friction_law[-1].max()) > 1e-3
    assert float(paper.friction_ratio.max()) > 2 * MU_S
    assert caught and "not passive" in str(caught[0].message)


def test_run_summary_line_reports_the_friction_law(tmp_path, capsys):
    """`workbench run` of a LuGre scene states the largest |F_t|/F_n and the times above mu_s
    and beyond the envelope, per joint."""
    from workbench.cli import main

    scene = tmp_path / "s.toml"
    scene.write_text(
        '[model]\nname = "ninebar"\n[effects]\nclearance = ["A"]\nfriction = "lugre"\n'
        '[solver]\nmethod = "ark548"\n[run]\nduration = 0.05\n[record]\ndt = 1e-4\n'
        'variables = ["contact_force"]\n'
    )
    assert main(["run", str(scene), "-o", str(tmp_path / "r.nc"), "-q"]) == 0
    line = capsys.readouterr().out.strip()
    assert "; LuGre |F_t|/F_n up to " in line and "time above mu_s = 0.15: A " in line
    assert "beyond 2 mu_s + sigma2 |v_t|: A 0 s" in line


def test_diagnostic_coefficient_takes_the_bristles_on_their_invariant_set():
    """The reported coefficient is the law's wherever the bristle deflection lies in |z| <=
    mu_s / s0, where the exact solution stays (Canudas de Wit et al. 1995); a z beyond it (an
    explicit method's stage or dense output) is taken at the edge of the set."""
    from workbench.models import get_model
    from workbench.models._clearance import friction_block
    from workbench.models._reduced import lugre_diagnostic

    params = get_model("ninebar").default_parameters()
    fp = tuple(friction_block(params))
    v = 0.17
    a = lugre_decay(v, S0, MU_K, MU_S, V_S, GAMMA)
    s1 = lugre_damping(v, PAPER_S1, 1e-3)
    for z in (-1.5e-6, 2e-7, 5e-7, 1.5e-6):
        law = lugre_coefficient(v, z, v - a * z, S0, s1, S2)
        assert lugre_diagnostic(v, z, a, S0, s1, fp) == pytest.approx(law, rel=1e-14)
    edge = lugre_coefficient(v, -MU_S / S0, v + a * MU_S / S0, S0, s1, S2)
    assert lugre_diagnostic(v, -1.4e-5, a, S0, s1, fp) == pytest.approx(edge, rel=1e-14)
    assert abs(edge) <= MU_S + S2 * v
