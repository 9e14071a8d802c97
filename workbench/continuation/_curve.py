"""Curves of bifurcations in two parameters: a fold, period doubling, Neimark-Sacker or grazing
point of a branch of periodic orbits continued in a second parameter, with the codimension-two
points on the curve that cost nothing beyond what the continuation computes.

A point of the curve is a periodic orbit of the stroboscopic map ``P^k(x; p, q)`` (state ``y``
at the strobe time, the live discrete states; :mod:`workbench.continuation._strobe`) at which a
*defining condition* holds; the unknowns are ``u = (y / s, aux[live], p / ps, q / qs[,
theta])``, the state scaled by its characteristic size at the curve's start, the two parameters
by the curve's scales. The equations are the orbit condition ``G = P^k(x) - x = 0`` (scaled),
the defining condition ``T = 0``, and the pseudo-arclength condition ``tau . (u - u_pred) = 0``
in all the unknowns (Keller 1977), so the curve passes turning points in either parameter and
cusps. The defining conditions are the *minimally augmented* ones of MatCont and
BifurcationKit (Govaerts 2000; Kuznetsov 2004, Sec. 10.2; for maps Govaerts, Khoshsiar
Ghaziani, Kuznetsov & Meijer 2007):

* **fold** (a multiplier +1) and **period doubling** (-1): ``T = g``, the last component of the
  solution of the bordered system ``[[M - lambda I, b], [c^T, 0]] [v; g] = [0; 1]`` with
  ``lambda = +1`` or ``-1``; ``g = 0`` exactly where ``M - lambda I`` is singular. The borders
  ``b`` and ``c`` are the left and right singular vectors of its smallest singular value at the
  start, then the normalised ``w`` and ``v`` of the last accepted point. Its derivative is
  ``g_z = -w^T M_z v`` (``w`` from the transposed system). In the state ``M_z v`` needs the
  map's second derivatives: by their symmetry, the row ``w^T M_y v`` is ``|v| w^T H`` with
  ``H = (M(u + eps v / |v|) - M(u)) / eps``, one more monodromy matrix whatever the dimension;
  in each parameter a forward difference of ``g`` with the borders held (one monodromy each).
* **Neimark-Sacker** (a pair ``e^{+-i theta}``): ``T = g`` of the bordered system of
  ``M (.) M - I``, the bialternate product (second compound matrix, whose eigenvalues are the
  products ``mu_i mu_j``, ``i < j``), singular where two multipliers multiply to 1: a complex
  pair on the unit circle, or a real pair ``mu, 1 / mu`` (a *neutral saddle*, not a
  bifurcation; such points are stored with kind ``neutral_saddle``). Its derivative in the
  state by forward differences of ``g`` along each unknown (one monodromy each).
* **grazing**: the orbit touches an event surface (a contact appears or a lasting one lifts
  off): with an extra unknown, the phase ``theta`` of the touch (``t* = t0 + theta k T``),
  ``T = (h(t*, x(t*)), dh/dt(t*, x(t*)))`` for the event function ``h`` whose local extremum
  along the orbit is zero (Nordmark 1991; di Bernardo, Budd, Champneys & Kowalczyk 2008). The
  state at ``t*`` and its derivative in the unknowns come from copies of the model integrated
  in one step sequence (:meth:`StrobeMap.flow`); ``dh/dt`` is a central difference along the
  vector field, its derivatives in the state and in time central differences of it (no
  integration); in each parameter a forward difference of the whole condition.

The orbit condition's columns: ``M - I`` in the state, forward differences of the map in each
parameter. All forward differences take the step ``sqrt(rtol)`` (scaled; the parameters: times
their scales): two integrations with their own step sequences differ by about ``rtol``, so a
difference over ``eps`` carries ``rtol / eps`` of noise and ``eps`` of truncation, both
``sqrt(rtol)`` at that step: a Jacobian this accurate makes Newton's method converge at a rate
of about ``sqrt(rtol)`` per iteration, while the point it converges to is set by the residual,
which is evaluated to ``rtol``.

**Codimension two.** Along the curve, sign changes of test functions located by the Illinois
method along the arclength (each trial point corrected onto the curve): the curve turns in
either parameter (the tangent's component); on a fold curve a **cusp** (the fold's normal-form
coefficient ``a = <w, B(v, v)> / (2 <w, v>)``, from ``H`` above), **1:1 resonance** (another
multiplier through +1), **fold-flip** (another through -1), **fold-Neimark-Sacker** (two others
multiply to 1); on a period-doubling curve **1:2 resonance** (another multiplier through -1),
fold-flip (another through +1), **flip-Neimark-Sacker**; on a Neimark-Sacker curve the strong
resonances **1:1, 1:2, 1:3, 1:4** (``kappa = cos theta`` of the critical pair through 1, -1,
-1/2, 0; past 1:1 and 1:2 the pair is real: a neutral saddle), fold-Neimark-Sacker and
flip-Neimark-Sacker; on a grazing curve the orbit's own **fold** and **period doubling**
(``det(M - I)``, ``det(M + I)``) and a **degenerate grazing** (the touch's curvature
``d^2h/dt^2`` through 0). Not detected: the generalised flip and the Chenciner point (their
normal-form coefficients need third derivatives of the map), double Neimark-Sacker, and a
second contact touching elsewhere along a grazing orbit.
"""

from __future__ import annotations

import importlib
import math
import time
from dataclasses import dataclass, field
from itertools import combinations

import numpy as np
import xarray as xr

from workbench._attributes import flag_meaning, flags, variable
from workbench.continuation._newton import NewtonFailure, live_changed, next_step, orbit_at
from workbench.continuation._orbits import _guess
from workbench.continuation._report import RangeProgress
from workbench.continuation._strobe import MapValue, StrobeMap
from workbench.models import get_model
from workbench.run import provenance
from workbench.scene import SceneSource, load_scene, scene_from_toml
from workbench.solver import SolverError

__all__ = ["CURVE_KINDS", "CURVE_LABELS", "continue_curve"]

#: the kind of each point of a curve (CF flag_values / flag_meanings of the stored ``kind``)
CURVE_KINDS = {
    "fold": 1,
    "period_doubling": 2,
    "neimark_sacker": 3,
    "grazing": 4,
    "neutral_saddle": 5,
}
#: the labels of a curve's points (CF flags of the stored ``label``)
CURVE_LABELS = {
    "regular": 0,
    "start": 1,
    "end": 2,
    "first_parameter_turn": 3,
    "second_parameter_turn": 4,
    "cusp": 5,
    "resonance_1_1": 6,
    "resonance_1_2": 7,
    "resonance_1_3": 8,
    "resonance_1_4": 9,
    "fold_flip": 10,
    "fold_neimark_sacker": 11,
    "flip_neimark_sacker": 12,
    "grazing_fold": 13,
    "grazing_period_doubling": 14,
    "degenerate_grazing": 15,
}
_TURNS = ("first_parameter_turn", "second_parameter_turn")
#: the codimension-two test functions of each kind of curve
TESTS = {
    "fold": (*_TURNS, "cusp", "resonance_1_1", "fold_flip", "fold_neimark_sacker"),
    "period_doubling": (*_TURNS, "resonance_1_2", "fold_flip", "flip_neimark_sacker"),
    "neimark_sacker": (
        *_TURNS,
        "resonance_1_1",
        "resonance_1_2",
        "resonance_1_3",
        "resonance_1_4",
        "fold_neimark_sacker",
        "flip_neimark_sacker",
    ),
    "grazing": (*_TURNS, "grazing_fold", "grazing_period_doubling", "degenerate_grazing"),
}
TEST_MEANINGS = {
    "first_parameter_turn": "tangent's component along the first parameter (0 where the curve "
    "turns back in it)",
    "second_parameter_turn": "tangent's component along the second parameter (0 where the "
    "curve turns back in it)",
    "cusp": "normal-form coefficient a of the fold, <w, B(v, v)> / (2 <w, v>) (0 at a cusp)",
    "resonance_1_1": "1:1 resonance test (0 where a second multiplier is +1; Neimark-Sacker "
    "curve: cos(theta) - 1)",
    "resonance_1_2": "1:2 resonance test (0 where a second multiplier is -1; Neimark-Sacker "
    "curve: cos(theta) + 1)",
    "resonance_1_3": "1:3 resonance test cos(theta) + 1/2",
    "resonance_1_4": "1:4 resonance test cos(theta)",
    "fold_flip": "fold-flip test (0 where a multiplier other than the critical one is -1 on a "
    "fold curve, +1 on a period-doubling curve)",
    "fold_neimark_sacker": "product of mu_i mu_j - 1 over the other multipliers (fold-"
    "Neimark-Sacker: 0 where two of them multiply to 1); Neimark-Sacker curve: product of "
    "mu - 1 over the others",
    "flip_neimark_sacker": "product of mu_i mu_j - 1 over the other multipliers (flip-"
    "Neimark-Sacker); Neimark-Sacker curve: product of mu + 1 over the others",
    "grazing_fold": "det(M - I) of the grazing orbit (0 at its fold)",
    "grazing_period_doubling": "det(M + I) of the grazing orbit (0 at its period doubling)",
    "degenerate_grazing": "curvature d2h/dt2 of the event function at the touch, scaled (0 at a "
    "degenerate grazing)",
}
#: a multiplier counts as complex when its imaginary part exceeds this fraction of its modulus
COMPLEX = 1e-6


# -- the map over two parameters ----------------------------------------------------------------
class _Family:
    """``P^k`` over two parameters: one :class:`StrobeMap` over the first parameter per value
    of the second, its Jacobian in the scaled unknowns of the curve's start (the state divided
    by ``s0``, the live discrete states; a state's characteristic size can depend on the
    parameters, the curve's scaling must not)."""

    KEEP = 8  # maps kept (a Newton iteration visits q and q + dq)

    def __init__(self, scene, p_name: str, q_name: str, *, periods, rtol, monodromy) -> None:
        self.scene = scene
        self.p_name, self.q_name = p_name, q_name
        model = get_model(scene.model)
        self.p_par, self.q_par = model.parameter(p_name), model.parameter(q_name)
        self._maps: dict[float, StrobeMap] = {}
        self._settings = {"periods": periods, "rtol": rtol, "monodromy": monodromy}
        first = self.map(float(scene.resolved_parameters[q_name]))
        self.periods, self.rtol, self.monodromy = first.periods, first.rtol, first.monodromy
        self.method, self.scene_method = first.method, first.scene_method
        self.s0 = first.scale()
        self.evaluations = 0

    def map(self, q: float) -> StrobeMap:
        key = float(q)
        if key not in self._maps:
            if len(self._maps) >= self.KEEP:
                self._maps.pop(next(iter(self._maps)))
            scene = self.scene.with_parameters(**{self.q_name: key})
            self._maps[key] = StrobeMap(scene, self.p_name, **self._settings)
        return self._maps[key]

    def check(self, p: float, q: float) -> str | None:
        """Why (p, q) is not allowed, or None."""
        for par, value in ((self.p_par, p), (self.q_par, q)):
            why = par.check(value)
            if why:
                return f"{par.name} = {value:.10g} {why}"
        return None

    def problem(self, p: float, q: float):
        return self.map(q).prepared(p).problem

    def span(self, p: float, q: float) -> float:
        return self.periods * self.map(q).prepared(p).period

    def _ratio(self, q: float) -> np.ndarray:
        return self.s0 / self.map(q).scale()

    def __call__(self, y, aux, p: float, q: float, *, tangent: bool = True) -> MapValue:
        """``P^k(y, aux; p, q)``, its Jacobian (with ``tangent``) in the curve's scaled
        unknowns."""
        try:
            v = self.map(q)(y, aux, p, tangent=tangent)
        except SolverError as exc:
            raise NewtonFailure(f"the map failed at ({p:.10g}, {q:.10g}): {exc}") from exc
        self.evaluations += 1
        if tangent:
            d = np.concatenate([1.0 / self._ratio(q), np.ones(v.live.size)])
            v.M = d[:, None] * v.M / d[None, :]
        return v

    def flow(self, y, aux, p: float, q: float, theta: float, live, *, jacobian: bool):
        """The time ``t0 + (theta mod 1) k T`` and the state, discrete state and (with
        ``jacobian``) derivative of the state there in the curve's scaled unknowns (states and
        live discrete states)."""
        smap = self.map(q)
        prep = smap.prepared(p)
        t = prep.problem.t0 + (theta % 1.0) * self.periods * prep.period
        try:
            z, a, W, active = smap.flow(y, aux, p, t, jacobian=jacobian)
        except SolverError as exc:
            raise NewtonFailure(f"the flow failed at ({p:.10g}, {q:.10g}): {exc}") from exc
        self.evaluations += 1
        if W is not None:
            n = np.asarray(y).size
            cols = np.concatenate([np.arange(n), n + np.searchsorted(active, live)]).astype(int)
            W = W[:, cols]
            W[:, :n] *= self._ratio(q)[None, :]
        return t, z, a, W


# -- defining systems ------------------------------------------------------------------------
def _bordered(A: np.ndarray, b: np.ndarray, c: np.ndarray):
    """``g``, ``v`` and ``w`` of ``[[A, b], [c^T, 0]] [v; g] = [0; 1]`` and its transpose."""
    k = A.shape[0]
    B = np.zeros((k + 1, k + 1))
    B[:k, :k], B[:k, k], B[k, :k] = A, b, c
    e = np.zeros(k + 1)
    e[k] = 1.0
    try:
        x = np.linalg.solve(B, e)
        z = np.linalg.solve(B.T, e)
    except np.linalg.LinAlgError as exc:
        raise NewtonFailure(f"singular bordered matrix ({exc})") from exc
    return float(x[k]), x[:k], z[:k]


def _borders(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    U, _, Vt = np.linalg.svd(A)
    return U[:, -1].copy(), Vt[-1].copy()


def _compound(M: np.ndarray) -> np.ndarray:
    """The bialternate product ``M (.) M`` (second compound matrix: the 2x2 minors over the
    index pairs ``i < j``), whose eigenvalues are ``mu_i mu_j``."""
    i, j = np.array(list(combinations(range(M.shape[0]), 2))).T
    return M[np.ix_(i, i)] * M[np.ix_(j, j)] - M[np.ix_(i, j)] * M[np.ix_(j, i)]


@dataclass
class _Eval:
    """The curve's equations at one value of the unknowns."""

    y: np.ndarray
    aux: np.ndarray
    p: float
    q: float
    extra: np.ndarray
    value: MapValue
    G: np.ndarray
    T: np.ndarray
    ctx: dict


class _Bordered:
    """Fold (``lam = +1``) or period doubling (``lam = -1``): ``M - lam I`` singular."""

    extra, rows = 0, 1

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self.lam = 1.0 if kind == "fold" else -1.0

    def _A(self, M):
        return M - self.lam * np.eye(M.shape[0])

    def start(self, fam, ev: _Eval) -> None:
        self.b, self.c = _borders(self._A(ev.value.M))

    def evaluate(self, fam, y, aux, p, q, extra, live):
        value = fam(y, aux, p, q)
        g, v, w = _bordered(self._A(value.M), self.b, self.c)
        return value, np.array([g]), {"v": v, "w": w}

    def perturbed(self, fam, y, aux, p, q, extra, live, ev):
        value = fam(y, aux, p, q)
        return value, np.array([_bordered(self._A(value.M), self.b, self.c)[0]])

    def state_rows(self, fam, ev: _Eval, live):
        v, w = ev.ctx["v"], ev.ctx["w"]
        nv = float(np.linalg.norm(v))
        vh = v / nv
        eps = math.sqrt(fam.rtol)
        n = ev.y.size
        aux = ev.aux.copy()
        aux[live] += eps * vh[n:]
        M2 = fam(ev.y + eps * fam.s0 * vh[:n], aux, ev.p, ev.q).M
        if M2.shape != ev.value.M.shape:
            raise NewtonFailure("the live discrete states changed along the null vector")
        H = (M2 - ev.value.M) / eps  # d/d eps of M along v / |v|
        cusp = 0.5 * float(w @ H @ vh) / float(w @ vh)
        return -nv * (w @ H)[None, :], {"cusp": cusp}

    def update(self, ev: _Eval) -> None:
        v, w = ev.ctx["v"], ev.ctx["w"]
        self.b, self.c = w / np.linalg.norm(w), v / np.linalg.norm(v)


class _NeimarkSacker(_Bordered):
    """Two multipliers multiply to 1: the bordered bialternate product ``M (.) M - I``."""

    def __init__(self) -> None:
        self.kind = "neimark_sacker"

    def _A(self, M):
        C = _compound(M)
        return C - np.eye(C.shape[0])

    def start(self, fam, ev: _Eval) -> None:
        if ev.value.M.shape[0] < 2:
            raise ValueError(
                "kind='neimark_sacker' needs at least two unknowns (a pair of multipliers)"
            )
        super().start(fam, ev)

    def state_rows(self, fam, ev: _Eval, live):
        eps = math.sqrt(fam.rtol)
        n, m = ev.y.size, ev.value.M.shape[0]
        row = np.empty(m)
        for j in range(m):
            y, aux = ev.y.copy(), ev.aux.copy()
            if j < n:
                y[j] += eps * fam.s0[j]
            else:
                aux[live[j - n]] += eps
            M2 = fam(y, aux, ev.p, ev.q).M
            if M2.shape != ev.value.M.shape:
                raise NewtonFailure("the live discrete states changed")
            row[j] = (_bordered(self._A(M2), self.b, self.c)[0] - ev.T[0]) / eps
        return row[None, :], {}


class _Grazing:
    """A local extremum of event function ``event`` along the orbit is zero: unknowns the
    orbit, the phase ``theta`` of the touch and the parameters; conditions ``h = 0`` and
    ``dh/dt = 0`` at the touch (scaled: ``h / hs``, ``dh/dt tscale / hs``)."""

    kind = "grazing"
    extra, rows = 1, 2

    def __init__(self, event: int) -> None:
        self.event = event
        self.hs = 1.0
        self.tscale = 1.0

    def _D(self, pb, t: float, z, a) -> np.ndarray:
        """(h, dh/dt) at (t, z): dh/dt by a central difference along the vector field."""
        hooks = importlib.import_module(pb.hooks)
        work = np.zeros(max(pb.work_size, 1))
        g = np.empty(pb.event_direction.size)
        f = np.empty(z.size)
        a = np.array(a, dtype=float)
        z = np.ascontiguousarray(z, dtype=float)

        def h(tt, x):
            hooks.event_values(tt, np.ascontiguousarray(x), pb.p, pb.ip, a, work, g)
            return float(g[self.event])

        hooks.rhs(t, z, pb.p, pb.ip, a, work, f)
        dt = 1e-5 * self.tscale  # truncation ~1e-10, rounding ~1e-11 of h's scale
        return np.array([h(t, z), (h(t + dt, z + dt * f) - h(t - dt, z - dt * f)) / (2 * dt)])

    def _along(self, pb, t, z, a, delta):
        """d/dt of (h, dh/dt) along the trajectory through (t, z) (central difference)."""
        hooks = importlib.import_module(pb.hooks)
        f = np.empty(z.size)
        work = np.zeros(max(pb.work_size, 1))
        hooks.rhs(t, np.ascontiguousarray(z, dtype=float), pb.p, pb.ip, np.array(a), work, f)
        up = self._D(pb, t + delta, z + delta * f, a)
        down = self._D(pb, t - delta, z - delta * f, a)
        return (up - down) / (2 * delta)

    def _scaled(self, D):
        return np.array([D[0] / self.hs, D[1] * self.tscale / self.hs])

    def start(self, fam, ev: _Eval) -> None:
        self.tscale = fam.span(ev.p, ev.q) / (2 * math.pi)
        t, z, a, _ = fam.flow(ev.y, ev.aux, ev.p, ev.q, ev.extra[0], [], jacobian=False)
        pb = fam.problem(ev.p, ev.q)
        dx = np.empty(z.size)
        for j in range(z.size):
            d = np.zeros(z.size)
            d[j] = 1e-5 * fam.s0[j]
            dx[j] = (self._D(pb, t, z + d, a)[0] - self._D(pb, t, z - d, a)[0]) / 2e-5
        # the event function's change per unit scaled state: h / hs compares with G
        self.hs = float(np.linalg.norm(dx)) or 1.0

    def _test(self, fam, y, aux, p, q, theta, live):
        t, z, a, _ = fam.flow(y, aux, p, q, theta, live, jacobian=False)
        D = self._D(fam.problem(p, q), t, z, a)
        return self._scaled(D), {"t": t, "z": z, "aux_t": a}

    def evaluate(self, fam, y, aux, p, q, extra, live):
        value = fam(y, aux, p, q)
        T, ctx = self._test(fam, y, aux, p, q, extra[0], live)
        return value, T, ctx

    def perturbed(self, fam, y, aux, p, q, extra, live, ev):
        value = fam(y, aux, p, q, tangent=False)
        return value, self._test(fam, y, aux, p, q, extra[0], live)[0]

    def state_rows(self, fam, ev: _Eval, live):
        t, z, a, W = fam.flow(ev.y, ev.aux, ev.p, ev.q, ev.extra[0], live, jacobian=True)
        pb = fam.problem(ev.p, ev.q)
        n = z.size
        Dx = np.empty((2, n))
        for j in range(n):
            d = np.zeros(n)
            d[j] = 1e-5 * fam.s0[j]  # central: truncation 1e-10, rounding of dh/dt 1e-6
            Dx[:, j] = (self._D(pb, t, z + d, a) - self._D(pb, t, z - d, a)) / (2e-5 * fam.s0[j])
        Dt = self._along(pb, t, z, a, 1e-4 * self.tscale)
        rows = np.empty((2, W.shape[1] + 1))
        rows[:, :-1] = Dx @ W[:n]
        rows[:, -1] = Dt * fam.span(ev.p, ev.q)  # d/d theta
        rows[0] /= self.hs
        rows[1] *= self.tscale / self.hs
        curvature = float(Dt[1]) * self.tscale**2 / self.hs
        return rows, {"curvature": curvature, "touch": z, "touch_time": t}

    def update(self, ev: _Eval) -> None:
        pass


def _system(kind: str, event: int | None):
    if kind in ("fold", "period_doubling"):
        return _Bordered(kind)
    if kind == "neimark_sacker":
        return _NeimarkSacker()
    return _Grazing(event or 0)


# -- points, the corrector and the tangent ------------------------------------------------------
@dataclass
class _Point:
    """A converged point of the curve: its unknowns, the equations there, the Jacobian of
    (G, T) (at the point or one Newton step before it), Newton's work, its tangent and
    codimension-two tests."""

    u: np.ndarray
    ev: _Eval
    J: np.ndarray
    iterations: int
    residual: float
    info: dict
    tau: np.ndarray | None = None
    tests: dict = field(default_factory=dict)

    @property
    def multipliers(self) -> np.ndarray:
        mu = np.linalg.eigvals(self.ev.value.M)
        return mu[np.lexsort((-mu.imag, -np.abs(mu)))]


@dataclass
class _Settings:
    tolerance: float = 1e-8
    step: float = 0.02
    max_step: float = 0.1
    min_step: float = 1e-6
    max_points: int = 200
    max_iterations: int = 8
    start_iterations: int = 30
    locate_tolerance: float = 1e-6  # scaled arclength


class _Curve:
    """The curve's unknowns, equations, corrector, tangent and tracer."""

    def __init__(self, fam, system, aux0, live, ps: float, qs: float, cfg: _Settings) -> None:
        self.fam, self.system, self.cfg = fam, system, cfg
        self.aux0 = np.array(aux0, dtype=float)
        self.live = np.asarray(live, dtype=int)
        self.n = fam.s0.size
        self.m = self.n + self.live.size
        self.N = self.m + 2 + system.extra
        self.ps, self.qs = float(ps), float(qs)

    # unknowns
    def encode(self, y, aux, p, q, extra) -> np.ndarray:
        y = np.asarray(y, float)
        live = np.asarray(aux, float)[self.live]
        return np.concatenate([y / self.fam.s0, live, [p / self.ps, q / self.qs], extra])

    def decode(self, u):
        m, n = self.m, self.n
        aux = self.aux0.copy()
        aux[self.live] = u[n:m]
        return (
            self.fam.s0 * u[:n],
            aux,
            float(u[m] * self.ps),
            float(u[m + 1] * self.qs),
            u[m + 2 :],
        )

    def rescale_p(self, pt: _Point, ps: float) -> None:
        """Measure the first parameter in units of ``ps`` from now on."""
        pt.u[self.m] *= self.ps / ps
        pt.J[:, self.m] *= ps / self.ps
        self.ps = float(ps)

    # equations
    def _residual(self, value: MapValue, y, aux) -> np.ndarray:
        return np.concatenate(
            [(value.y1 - y) / self.fam.s0, value.aux1[self.live] - aux[self.live]]
        )

    def evaluate(self, u) -> _Eval:
        y, aux, p, q, extra = self.decode(u)
        why = self.fam.check(p, q)
        if why:
            raise NewtonFailure(f"the curve leaves the parameters' valid range ({why})")
        value, T, ctx = self.system.evaluate(self.fam, y, aux, p, q, extra, self.live)
        if not np.array_equal(value.live, self.live):
            raise NewtonFailure(live_changed(value, self.fam.periods, self.live.size))
        return _Eval(y, aux, p, q, np.array(extra), value, self._residual(value, y, aux), T, ctx)

    def jacobian(self, ev: _Eval) -> tuple[np.ndarray, dict]:
        m, fam = self.m, self.fam
        J = np.zeros((m + self.system.rows, self.N))
        J[:m, :m] = ev.value.M - np.eye(m)
        rows, info = self.system.state_rows(fam, ev, self.live)
        J[m:, :m] = rows[:, :m]
        J[m:, m + 2 :] = rows[:, m:]
        h = math.sqrt(fam.rtol)  # forward differences: see the module docstring
        for col, scale in ((m, self.ps), (m + 1, self.qs)):
            d = h * scale
            p2, q2 = (ev.p + d, ev.q) if col == m else (ev.p, ev.q + d)
            if fam.check(p2, q2):  # at the edge of the valid range: the other side
                d = -d
                p2, q2 = (ev.p + d, ev.q) if col == m else (ev.p, ev.q + d)
            value, T2 = self.system.perturbed(fam, ev.y, ev.aux, p2, q2, ev.extra, self.live, ev)
            J[:m, col] = (self._residual(value, ev.y, ev.aux) - ev.G) / (d / scale)
            J[m:, col] = (T2 - ev.T) / (d / scale)
        return J, info

    def correct(self, u0, u_pred, tau, max_iterations: int) -> _Point:
        """Newton's method on (G, T) = 0 and ``tau . (u - u_pred) = 0`` from ``u0``."""
        u = np.array(u0, dtype=float)
        J, info = None, {}
        r = math.inf
        for it in range(max_iterations + 1):
            ev = self.evaluate(u)
            F = np.concatenate([ev.G, ev.T])
            r = float(np.max(np.abs(F)))
            arc = float(tau @ (u - u_pred))
            if not np.isfinite(r):
                break
            if r < self.cfg.tolerance and abs(arc) < self.cfg.tolerance:
                if J is None:
                    J, info = self.jacobian(ev)
                else:  # the exact block at the point itself
                    J[: self.m, : self.m] = ev.value.M - np.eye(self.m)
                return _Point(u, ev, J, it, r, info)
            if it == max_iterations:
                break
            J, info = self.jacobian(ev)
            A = np.vstack([J, tau])
            try:
                step = np.linalg.solve(A, -np.concatenate([F, [arc]]))
            except np.linalg.LinAlgError as exc:
                raise NewtonFailure(f"singular Newton matrix ({exc})") from exc
            if not np.all(np.isfinite(step)):
                raise NewtonFailure("the Newton step is not finite (singular matrix)")
            u = u + step
        y, aux, p, q, _ = self.decode(u)
        raise NewtonFailure(
            f"the corrector did not converge near ({p:.10g}, {q:.10g}) (scaled residual "
            f"{r:.3g}, tolerance {self.cfg.tolerance:.3g})"
        )

    def tangent(self, pt: _Point, orientation: np.ndarray) -> np.ndarray:
        A = np.vstack([pt.J, orientation])
        e = np.zeros(self.N)
        e[-1] = 1.0
        try:
            t = np.linalg.solve(A, e)
        except np.linalg.LinAlgError as exc:
            raise NewtonFailure(f"no tangent ({exc})") from exc
        t /= np.linalg.norm(t)
        return t if t @ orientation >= 0 else -t

    # codimension two
    def tests(self, pt: _Point) -> dict:
        mu = pt.multipliers
        kind = self.system.kind
        out = {"first_parameter_turn": float(pt.tau[self.m])}
        out["second_parameter_turn"] = float(pt.tau[self.m + 1])
        crit = _critical(kind, mu)
        others = np.delete(mu, crit)
        minus, plus = np.prod(others - 1.0).real, np.prod(others + 1.0).real
        pairs = float(np.prod([a * b - 1.0 for a, b in combinations(others, 2)]).real)
        if kind == "fold":
            out.update(cusp=pt.info.get("cusp", math.nan), resonance_1_1=minus)
            out.update(fold_flip=plus, fold_neimark_sacker=pairs)
        elif kind == "period_doubling":
            out.update(resonance_1_2=plus, fold_flip=minus, flip_neimark_sacker=pairs)
        elif kind == "neimark_sacker":
            kappa = float(np.mean(mu[crit]).real)
            out.update(resonance_1_1=kappa - 1.0, resonance_1_2=kappa + 1.0)
            out.update(resonance_1_3=kappa + 0.5, resonance_1_4=kappa)
            out.update(fold_neimark_sacker=minus, flip_neimark_sacker=plus)
        else:
            out.update(
                grazing_fold=float(np.prod(mu - 1.0).real),
                grazing_period_doubling=float(np.prod(mu + 1.0).real),
                degenerate_grazing=pt.info.get("curvature", math.nan),
            )
        return out

    def at(self, A: _Point, sigma: float) -> _Point:
        """The curve's point at arclength ``sigma`` from A along A's tangent, with its tangent
        and tests."""
        u_pred = A.u + sigma * A.tau
        B = self.correct(u_pred, u_pred, A.tau, self.cfg.max_iterations)
        B.tau = self.tangent(B, A.tau)
        B.tests = self.tests(B)
        return B

    def locate(self, A: _Point, B: _Point, h: float, name: str):
        """The zero of test ``name`` between A and B (B at arclength h from A) by the Illinois
        method; (sigma, point), or None where it is not resolved (a trial failed, or the
        bracket did not shrink to the tolerance)."""
        lo, hi = 0.0, h
        f_lo, f_hi = A.tests[name], B.tests[name]
        side, found = 0, None
        for _ in range(40):
            if hi - lo < self.cfg.locate_tolerance:
                break
            mid = hi - f_hi * (hi - lo) / (f_hi - f_lo) if f_hi != f_lo else 0.5 * (lo + hi)
            if not lo < mid < hi:
                mid = 0.5 * (lo + hi)
            try:
                pt = self.at(A, mid)
            except NewtonFailure:
                return None
            f = pt.tests[name]
            found = (mid, pt)
            if f == 0.0:
                return found
            if np.sign(f) == np.sign(f_lo):
                lo, f_lo = mid, f
                if side == -1:
                    f_hi /= 2.0
                side = -1
            else:
                hi, f_hi = mid, f
                if side == 1:
                    f_lo /= 2.0
                side = 1
        return found if hi - lo < self.cfg.locate_tolerance else None

    def boundary(self, A: _Point, B: _Point, index: int, value: float) -> _Point:
        """The curve's point between A and B where unknown ``index`` equals ``value``."""
        frac = (value - A.u[index]) / (B.u[index] - A.u[index])
        u0 = A.u + frac * (B.u - A.u)
        u0[index] = value
        e = np.zeros(self.N)
        e[index] = 1.0
        pt = self.correct(u0, u0, e, self.cfg.max_iterations)
        pt.tau = self.tangent(pt, A.tau)
        pt.tests = self.tests(pt)
        return pt

    def trace(self, first: _Point, tau: np.ndarray, q_range, p_range, report=None) -> _Traced:
        """Continue from ``first`` along ``tau`` until the second parameter leaves
        ``q_range`` (the last point on its edge), the first leaves ``p_range`` or its valid
        range, the curve closes, the step falls below its least or ``max_points`` points
        are found; ``report(second parameter, points)`` after each point (progress)."""
        cfg = self.cfg
        first.tau = tau
        first.tests = self.tests(first)
        out = _Traced([first], ["start"])
        bounds = [(self.m + 1, q_range[0] / self.qs, q_range[1] / self.qs)]
        if p_range is not None:
            bounds.append((self.m, p_range[0] / self.ps, p_range[1] / self.ps))
        A, h = first, cfg.step
        while len(out.points) < cfg.max_points:
            try:
                B = self.at(A, h)
            except NewtonFailure as exc:
                h /= 2.0
                if h < cfg.min_step:
                    out.ended = f"the corrector failed at the least step ({exc})"
                    break
                continue
            if float(A.tau @ B.tau) < 0.5:  # too sharp a turn
                h /= 2.0
                if h < cfg.min_step:
                    out.ended = "the curve turns sharply however short the step"
                    break
                continue
            # the range: the last point on its edge
            edge = None
            for index, lo, hi in bounds:
                if not lo <= B.u[index] <= hi:
                    value = lo if B.u[index] < lo else hi
                    try:
                        edge = (index, self.boundary(A, B, index, value))
                    except NewtonFailure:
                        edge = (index, None)
                    break
            if edge is not None and edge[1] is not None:
                B = edge[1]
                h = float(np.linalg.norm(B.u - A.u))
            found = []
            for name in TESTS[self.system.kind]:
                fa, fb = A.tests[name], B.tests[name]
                if np.isfinite(fa) and np.isfinite(fb) and np.sign(fa) * np.sign(fb) < 0:
                    located = self.locate(A, B, h, name)
                    if located is None:
                        out.unresolved.append(
                            f"{name} between ({A.ev.p:.10g}, {A.ev.q:.10g}) and "
                            f"({B.ev.p:.10g}, {B.ev.q:.10g})"
                        )
                    else:
                        found.append((located[0], name, located[1]))
            for _, name, pt in sorted(found, key=lambda f: f[0]):
                out.points.append(pt)
                out.labels.append(name)
            self.system.update(B.ev)
            if edge is not None:
                which = "second" if edge[0] == self.m + 1 else "first"
                if edge[1] is None:
                    out.ended = f"the {which} parameter left its range (its edge not reached)"
                    break
                out.points.append(B)
                out.labels.append("end")
                out.ended = f"the {which} parameter reached the end of its range"
                break
            out.points.append(B)
            out.labels.append("regular")
            if report is not None:
                report(B.ev.q, len(out.points))
            if len(out.points) > 3 and np.linalg.norm(B.u - first.u) < 0.5 * h:
                out.ended = "the curve closed"
                break
            A = B
            h = next_step(h, B.iterations, cfg.max_step)
        else:
            out.ended = f"{cfg.max_points} points reached"
        if out.labels[-1] == "regular":
            out.labels[-1] = "end"
        if report is not None:
            report(out.points[-1].ev.q, len(out.points))
        return out


@dataclass
class _Traced:
    points: list
    labels: list
    ended: str = ""
    unresolved: list = field(default_factory=list)


def _critical(kind: str, mu: np.ndarray) -> np.ndarray:
    """Indices of the critical multiplier(s) of a curve of ``kind``."""
    if kind == "fold":
        return np.array([int(np.argmin(np.abs(mu - 1.0)))])
    if kind == "period_doubling":
        return np.array([int(np.argmin(np.abs(mu + 1.0)))])
    if kind == "neimark_sacker" and mu.size >= 2:
        pairs = list(combinations(range(mu.size), 2))
        best = min(pairs, key=lambda ij: abs(mu[ij[0]] * mu[ij[1]] - 1.0))
        return np.array(best)
    return np.zeros(0, dtype=int)


def _point_kind(kind: str, mu: np.ndarray) -> str:
    if kind == "neimark_sacker":
        c = mu[_critical(kind, mu)]
        if np.all(np.abs(c.imag) <= COMPLEX * np.abs(c)):
            return "neutral_saddle"
    return kind


# -- where a curve starts ----------------------------------------------------------------------
@dataclass
class _Start:
    """A curve's first point as given: the scene (at the second parameter's start value), the
    first parameter and its value, the orbit (state, discrete state, period), the kind, and
    the settings the branch was computed with."""

    scene: object
    parameter: str
    kind: str
    p: float
    y: np.ndarray
    aux: np.ndarray
    periods: int
    pscale: float
    rtol: float | None = None
    tolerance: float | None = None
    monodromy: str | None = None
    source: str = ""


def _from_branch(branch: xr.Dataset, kind: str | None, bifurcation: int | None) -> _Start:
    """The labelled point of a branch of :func:`continue_orbit` to start from: number
    ``bifurcation`` of its ``bifurcation`` dim, else the first of ``kind``, else the first
    fold, period doubling, Neimark-Sacker or grazing."""
    for key in ("scene", "continuation_parameter"):
        if key not in branch.attrs or (key == "continuation_parameter" and not branch.attrs[key]):
            raise ValueError(
                f"the dataset has no {key!r} attribute: pass a branch of "
                "workbench.continuation.continue_orbit (or a scene with parameter and value)"
            )
    P = branch.attrs["continuation_parameter"]
    found = [flag_meaning(branch.bifurcation_label, c) for c in branch.bifurcation_label.values]
    if "bifurcation_resolved" in branch:  # an unresolved bifurcation is no start
        found = [
            k if ok else "unresolved"
            for k, ok in zip(found, branch.bifurcation_resolved.values, strict=True)
        ]
    where = ", ".join(
        f"{k} at {P} = {float(p):.8g}"
        for k, p in zip(found, branch.bifurcation_parameter.values, strict=True)
    )
    if bifurcation is not None:
        if not 0 <= bifurcation < len(found):
            raise ValueError(
                f"bifurcation={bifurcation!r}: the branch has {len(found)} located "
                f"bifurcation(s) ({where or 'none'}); give an index below {len(found)}"
            )
        if found[bifurcation] not in KIND_NAMES or (kind and found[bifurcation] != kind):
            raise ValueError(
                f"bifurcation={bifurcation!r} is a {found[bifurcation]}; a curve starts at a "
                f"{kind or 'fold, period_doubling, neimark_sacker or grazing'} point"
            )
        i = bifurcation
    else:
        allowed = (kind,) if kind else KIND_NAMES
        hits = [i for i, k in enumerate(found) if k in allowed]
        if not hits:
            want = kind or "fold, period_doubling, neimark_sacker or grazing"
            raise ValueError(
                f"no {want} point located on the branch over {P} (found: {where or 'none'})"
            )
        i = hits[0]
    p = float(branch.bifurcation_parameter.values[i])
    r = int(branch.bifurcation_point.values[i])
    if r < 0:  # pragma: no cover - a branch dataset holds its located points
        raise ValueError(f"the branch holds no point at its {found[i]} ({P} = {p!r})")
    scene = scene_from_toml(branch.attrs["scene"])
    pb = StrobeMap(scene, None).prepared(math.nan).problem
    y = pb.y0.copy()
    for j, q in enumerate(pb.states):
        if f"orbit_{q.name}" in branch:
            y[j] = float(branch[f"orbit_{q.name}"].values[r])
    aux = (
        branch.orbit_discrete_state.values[r].astype(float)
        if "orbit_discrete_state" in branch
        else pb.aux0.copy()
    )
    values = branch[P].values
    span = float(np.nanmax(values) - np.nanmin(values))
    return _Start(
        scene=scene,
        parameter=P,
        kind=found[i],
        p=p,
        y=y,
        aux=aux,
        periods=int(branch.periods.values[r]),
        pscale=span if span > 0 else abs(p) or 1.0,
        rtol=float(branch.attrs["rtol"]) if "rtol" in branch.attrs else None,
        tolerance=float(branch.attrs["tolerance"]) if "tolerance" in branch.attrs else None,
        monodromy=branch.attrs.get("monodromy"),
        source=f"the {found[i]} at {P} = {p:.10g} of a branch of periodic orbits",
    )


KIND_NAMES = ("fold", "period_doubling", "neimark_sacker", "grazing")


def _touch(smap: StrobeMap, y, aux, p: float, event: int | None):
    """The local extremum of an event function along the orbit nearest zero relative to the
    function's range (of event function ``event``, or of any): ``(event, theta, value)``,
    ``theta`` its phase (fraction of the ``k`` periods from the strobe time), ``value`` in the
    event function's units. Read off the orbit's contact sequence
    (:meth:`StrobeMap.contact_sequence`), which reads a margin near a grazing again denser
    until two densities agree: a dip narrower than the samples' spacing (the nine-bar's
    lift-off, 0.1 nm deep and a few microseconds wide) is found where a fixed sampling
    picks another extremum."""
    ne = smap.prepared(p).problem.event_direction.size
    if ne == 0:
        raise ValueError(f"kind='grazing': model {smap.scene.model!r} has no event functions")
    if event is not None and not 0 <= event < ne:
        raise ValueError(f"event={event!r}: the model has {ne} event functions (0 .. {ne - 1})")
    seq = smap.contact_sequence(np.asarray(y, float), np.asarray(aux, float), p)
    if event is None:
        k, phase, value = seq.smallest_margin()
    elif seq.extrema[event].shape[0]:
        k, j = event, int(np.argmin(seq.margin(event)))
        phase, value = float(seq.extrema[k][j, 0]), float(seq.extrema[k][j, 1])
    else:
        k = -1
    if k < 0:
        raise ValueError("kind='grazing': no local extremum of an event function along the orbit")
    return k, (phase / seq.span) % 1.0, value


# -- the dataset --------------------------------------------------------------------------------
METHOD = (
    "a codimension-one bifurcation of periodic orbits of the stroboscopic map continued in two "
    "parameters by pseudo-arclength in all the unknowns; minimally augmented defining systems "
    "(bordered M - I, M + I, bialternate product M (.) M - I; grazing: h = dh/dt = 0 at the "
    "touch, its phase an unknown); codimension-two points from sign changes of test functions, "
    "located by the Illinois method"
)


def _dataset(tr_points, tr_labels, curve: _Curve, start: _Start, q_name, meta) -> xr.Dataset:
    fam = curve.fam
    kind = curve.system.kind
    pb = fam.problem(start.p, float(start.scene.resolved_parameters[q_name]))
    states = [q for q in pb.states if not q.name.startswith("_")]
    index = {q.name: i for i, q in enumerate(pb.states)}
    n = len(tr_points)
    mus = [pt.multipliers for pt in tr_points]
    m = max(mu.size for mu in mus)
    mu = np.full((n, m), np.nan + 0j)
    for i, x in enumerate(mus):
        mu[i, : x.size] = x
    model = get_model(fam.scene.model)
    data: dict = {}
    for name in (start.parameter, q_name):
        par = model.parameter(name)
        which = "first" if name == start.parameter else "second"
        values = np.array([pt.ev.p if name == start.parameter else pt.ev.q for pt in tr_points])
        data[name] = (
            "curve_point",
            values,
            variable(par.long_name, par.units, comment=f"the curve's {which} parameter"),
        )
    for q in states:
        y = np.array([pt.ev.y[index[q.name]] for pt in tr_points])
        data[f"orbit_{q.name}"] = (
            "curve_point",
            y,
            variable(f"{q.long_name} on the orbit at the strobe time", q.units),
        )
    na = pb.aux0.size
    if na:
        data["orbit_discrete_state"] = (
            ("curve_point", "discrete_state"),
            np.array([pt.ev.aux for pt in tr_points]).reshape(n, na),
            variable(
                "the model's discrete state on the orbit at the strobe time (the mechanisms: "
                "each joint's contact onset velocity)",
                model.discrete_state_units,
            ),
        )
    cm = ("curve_point", "multiplier")
    data["multiplier_real"] = (cm, mu.real, variable("real part of a Floquet multiplier"))
    data["multiplier_imag"] = (cm, mu.imag, variable("imaginary part of a Floquet multiplier"))
    data["multiplier_modulus"] = (cm, np.abs(mu), variable("modulus of a Floquet multiplier"))
    crit = np.full(n, np.nan + 0j)
    kinds = np.empty(n, np.int8)
    for i, x in enumerate(mus):
        c = x[_critical(kind, x)]
        if c.size:
            crit[i] = c[np.argmax(c.imag)] if c.size > 1 else c[0]
        kinds[i] = CURVE_KINDS[_point_kind(kind, x)]
    long_name = "part of the critical multiplier (+1 fold, -1 period doubling, e^(i theta) "
    long_name += "Neimark-Sacker with theta >= 0; none for grazing)"
    data["critical_real"] = ("curve_point", crit.real, variable(f"real {long_name}"))
    data["critical_imag"] = ("curve_point", crit.imag, variable(f"imaginary {long_name}"))
    data["kind"] = (
        "curve_point",
        kinds,
        flags(
            "kind of the bifurcation at the curve point",
            {v: k for k, v in CURVE_KINDS.items()},
            comment="fold: a multiplier +1; period_doubling: -1; neimark_sacker: a complex "
            "pair on the unit circle; grazing: the orbit touches an event surface; "
            "neutral_saddle: on a Neimark-Sacker curve, a real pair mu, 1/mu (no bifurcation)",
        ),
    )
    data["label"] = (
        "curve_point",
        np.array([CURVE_LABELS[lab] for lab in tr_labels], np.int8),
        flags(
            "kind of the curve point",
            {v: k for k, v in CURVE_LABELS.items()},
            comment="codimension-two points where a test function changes sign (located); "
            + "; ".join(f"{k}: {v}" for k, v in TEST_MEANINGS.items()),
        ),
    )
    for name in TESTS[kind]:
        data[f"test_{name}"] = (
            "curve_point",
            np.array([pt.tests.get(name, np.nan) for pt in tr_points]),
            variable(TEST_MEANINGS[name]),
        )
    data["newton_iterations"] = (
        "curve_point",
        np.array([pt.iterations for pt in tr_points], np.int32),
        variable("Newton iterations of the point"),
    )
    data["residual"] = (
        "curve_point",
        np.array([pt.residual for pt in tr_points]),
        variable("largest scaled residual of the orbit and defining conditions"),
    )
    if kind == "grazing":
        span = np.array([fam.span(pt.ev.p, pt.ev.q) for pt in tr_points])
        theta = np.array([pt.ev.extra[0] % 1.0 for pt in tr_points])
        data["touch_time"] = (
            "curve_point",
            theta * span,
            variable("time of the touch after the strobe time", "s"),
        )
        for q in states:
            data[f"touch_{q.name}"] = (
                "curve_point",
                np.array([pt.ev.ctx["z"][index[q.name]] for pt in tr_points]),
                variable(f"{q.long_name} where the orbit touches the event surface", q.units),
            )
    special = [i for i, lab in enumerate(tr_labels) if lab not in ("regular", "start", "end")]
    data["special_label"] = (
        "special_point",
        np.array([CURVE_LABELS[tr_labels[i]] for i in special], np.int8),
        dict(data["label"][2], long_name="kind of the codimension-two point"),
    )
    data["special_index"] = (
        "special_point",
        np.array(special, np.int32),
        variable("index of the point along the curve"),
    )
    coords = {
        "curve_point": ("curve_point", np.arange(n), variable("index along the curve")),
        "multiplier": ("multiplier", np.arange(m), variable("multiplier (largest modulus first)")),
        "special_point": (
            "special_point",
            np.arange(len(special)),
            variable("located codimension-two point"),
        ),
    }
    if na:
        coords["discrete_state"] = ("discrete_state", np.arange(na), variable("discrete state"))
    ds = xr.Dataset(data, coords=coords)
    scene = fam.scene.with_parameters(**{start.parameter: start.p})
    ds.attrs.update(provenance(scene, by="workbench.continuation.continue_curve"))
    ds.attrs.update(
        title=f"{kind.replace('_', ' ')} curve of model {fam.scene.model} in "
        f"({start.parameter}, {q_name})",
        continuation_parameter=start.parameter,
        curve_parameter=q_name,
        curve_kind=kind,
        curve_start=start.source,
        periods=np.int32(fam.periods),
        method=METHOD,
        monodromy=fam.monodromy,
        integration_method=fam.method,
        scene_method=fam.scene_method,
        rtol=fam.rtol,
        **meta,
    )
    if kind == "grazing":
        ds.attrs["grazing_event"] = np.int32(curve.system.event)
    return ds


def _run(
    fam,
    system,
    y,
    aux,
    p0: float,
    q0: float,
    extra,
    ends,
    pscale: float,
    cfg,
    p_range,
    progress=False,
):
    """The curve through the orbit (y, aux) near (p0, q0) (a point of the defining system,
    Newton's method with the second parameter held at ``q0``), followed toward each of
    ``ends`` (values of the second parameter) other than ``q0``: ``(curve, points, labels,
    halves)``, the points from the first end to the second; ``progress``: each way's on
    stderr."""
    value = fam(y, aux, p0, q0)
    q_lo, q_hi = min(ends), max(ends)
    qs = q_hi - q_lo
    curve = _Curve(fam, system, aux, value.live, pscale, qs, cfg)
    system.start(fam, _Eval(y, aux, p0, q0, np.array(extra, float), value, None, None, {}))
    u0 = curve.encode(y, aux, p0, q0, extra)
    e_q = np.zeros(curve.N)
    e_q[curve.m + 1] = 1.0
    first = curve.correct(u0, u0, e_q, cfg.start_iterations)
    system.update(first.ev)
    # the first parameter's scale: its change along the curve per |stop - start| of the second
    tau = curve.tangent(first, e_q)
    slope = abs(tau[curve.m] * curve.ps) / max(abs(tau[curve.m + 1] * qs), 1e-12)
    curve.rescale_p(first, float(np.clip(slope * qs, 1e-3 * pscale, 1e3 * pscale)))
    halves = []
    for end in ends:
        if end == q0:
            continue
        toward = math.copysign(1.0, end - q0) * e_q
        tau = curve.tangent(first, toward)
        if tau[curve.m + 1] * (end - q0) < 0:  # tangent to q = const: push toward the end
            tau = -tau
        copy = _Point(
            first.u.copy(),
            first.ev,
            first.J.copy(),
            first.iterations,
            first.residual,
            dict(first.info),
        )
        system.update(first.ev)
        report = RangeProgress(progress, fam.q_name, q0, end, "curve")
        try:
            halves.append(curve.trace(copy, tau, (q_lo, q_hi), p_range, report))
        finally:
            report.close()
    # stored from the first end to the second: the way toward the first end reversed, its
    # tangents (and the turning tests, their components) turned to point along the curve
    backward = halves[0] if ends[0] != q0 else None
    if backward is not None:
        for pt in backward.points:
            pt.tau = -pt.tau
            for name in _TURNS:
                pt.tests[name] = -pt.tests[name]
    if len(halves) == 2:
        a, b = halves
        points = a.points[::-1] + b.points[1:]
        labels = a.labels[::-1] + b.labels[1:]
    else:
        points, labels = halves[0].points, halves[0].labels
        if backward is not None:
            points, labels = points[::-1], labels[::-1]
    return curve, points, labels, halves


# -- the public function ------------------------------------------------------------------------
def continue_curve(
    source: xr.Dataset | SceneSource,
    second_parameter: str,
    *,
    stop: float,
    start: float | None = None,
    kind: str | None = None,
    bifurcation: int | None = None,
    parameter: str | None = None,
    value: float | None = None,
    state=None,
    discrete_state=None,
    periods: int = 1,
    event: int | None = None,
    parameter_range: tuple[float, float] | None = None,
    tolerance: float | None = None,
    rtol: float | None = None,
    monodromy: str | None = None,
    step: float = 0.02,
    max_step: float = 0.1,
    max_points: int = 200,
    progress: bool = False,
) -> xr.Dataset:
    """Continue a fold, period doubling, Neimark-Sacker or grazing point of periodic orbits in
    a second parameter: the curve of that bifurcation in the plane of two parameters, with its
    codimension-two points (the defining systems and tests:
    :mod:`workbench.continuation._curve`).

    Parameters
    ----------
    source : Dataset, or Scene, path or mapping
        A branch of :func:`continue_orbit` (the curve starts at one of its located
        bifurcations: the first parameter is the branch's, the orbit the one stored at that
        point, the integration tolerance, Newton's tolerance and the monodromy the branch's);
        or a forced scene, with ``parameter``, ``value`` (optional) and ``kind``: the curve
        starts from the orbit near ``value`` (Newton's method on the whole defining system,
        from ``state`` or the state after the scene's transient).
    second_parameter : str
        The model parameter the bifurcation is continued in (SI units).
    stop : float
        The curve is followed until the second parameter leaves the range between ``start``
        and ``stop`` (its last point on the edge of the range).
    start : float, optional
        The other end of the range (default the scene's value of ``second_parameter``, where
        the curve starts); with a value on the other side of the scene's, the curve is
        followed both ways from the scene's value.
    kind : str, optional
        ``"fold"``, ``"period_doubling"``, ``"neimark_sacker"`` or ``"grazing"``: with a
        branch, its first located point of this kind (default: its first of any of these);
        needed with a scene.
    bifurcation : int, optional
        With a branch: the index of the point in its ``bifurcation`` dim.
    parameter, value : str, float
        With a scene: the first parameter and its value near the bifurcation (default the
        scene's).
    state, discrete_state : optional
        With a scene: Newton's start (see :func:`periodic_orbit`).
    periods : int
        With a scene: the orbit's period in forcing periods.
    event : int, optional
        Grazing: the event function whose local extremum touches zero (default the one
        whose local extremum along the orbit is nearest zero at the start).
    parameter_range : (float, float), optional
        Bounds on the first parameter (it always stays in its valid range).
    tolerance : float, optional
        Newton's tolerance on the scaled residuals (default the branch's, or 1e-8).
    rtol : float, optional
        Integration tolerance (default the branch's, or ``min(scene rtol, 1e-9)``).
    monodromy : str, optional
        ``"tangent"``, ``"copies"`` or ``"auto"`` (see :func:`periodic_orbit`).
    step, max_step : float
        First and largest arclength step in the scaled unknowns (states by their sizes, the
        second parameter by ``|stop - start|``, the first by the curve's slope at its start
        times that).
    max_points : int
        Points at most each way from the start.
    progress : bool
        Show on stderr how much of its range each way of the curve has covered, and where it
        is (:class:`workbench._progress.Progress`).

    Returns
    -------
    xarray.Dataset
        Dim ``curve_point`` along the curve (from the ``start`` end to the ``stop`` end,
        codimension-two points in their place), ``multiplier`` and ``special_point``: both
        parameters (named after them, with their units), ``orbit_<state>``, the multipliers
        (``multiplier_real``, ``multiplier_imag``, ``multiplier_modulus``), the critical one
        (``critical_real``, ``critical_imag``), ``kind`` (CF flags: fold, period_doubling,
        neimark_sacker, grazing, neutral_saddle), ``label`` (CF flags: regular, start, end and
        the codimension-two points), the test functions ``test_<name>`` behind the labels,
        ``newton_iterations`` and ``residual``; a grazing curve also ``touch_time`` (s after
        the strobe time) and ``touch_<state>`` (where the orbit touches the event surface);
        per located codimension-two point ``special_label`` and ``special_index``.
        Attributes: the scene, both parameters, the kind, how each way ended, the cost.

    Raises
    ------
    ValueError
        A parameter that is not the model's, a range that does not contain the start, a
        branch without a point of the kind asked for, a scene without ``parameter`` or
        ``kind``.
    RuntimeError
        Newton's method did not converge at the start (:class:`NewtonFailure`).

    Examples
    --------
    >>> from workbench.continuation import continue_orbit
    >>> branch = continue_orbit({"model": {"name": "duffing"}, "parameters": {"gamma": 0.25},
    ...                          "run": {"transient_cycles": 100}}, "gamma", stop=0.27)
    >>> c = continue_curve(branch, "omega", start=1.15, stop=1.25)
    >>> c.attrs["curve_kind"], float(c.omega[0]), float(c.omega[-1])
    ('period_doubling', 1.15, 1.25)
    """
    wall0 = time.perf_counter()
    if kind is not None and kind not in KIND_NAMES:
        raise ValueError(f"kind={kind!r}; allowed: {', '.join(map(repr, KIND_NAMES))}")
    if isinstance(source, xr.Dataset):
        given = [
            k
            for k, v in (
                ("parameter", parameter),
                ("value", value),
                ("state", state),
                ("discrete_state", discrete_state),
            )
            if v is not None
        ]
        if given:
            raise ValueError(
                f"{'=, '.join(given)}= start a curve from a scene; a branch starts it at its "
                "own labelled point (choose it with kind= or bifurcation=)"
            )
        st = _from_branch(source, kind, bifurcation)
        tolerance = st.tolerance if tolerance is None else tolerance
        rtol = st.rtol if rtol is None else rtol
        monodromy = st.monodromy if monodromy is None else monodromy
    else:
        if parameter is None or kind is None:
            raise ValueError(
                "a curve from a scene needs parameter= (the first parameter) and kind= (or "
                "pass a branch of continue_orbit)"
            )
        scene = load_scene(source)
        scene = scene.replace(sweep={}) if scene.sweep else scene
        smap = StrobeMap(
            scene, parameter, periods=periods, rtol=rtol, monodromy=monodromy or "auto"
        )
        p = smap.value if value is None else float(value)
        y, aux = _guess(smap, p, state, discrete_state, None)
        st = _Start(scene, parameter, kind, p, y, aux, periods, abs(p) or 1.0)
        st.source = f"a {kind} near {parameter} = {p:.10g} given by state and value"
    tolerance = 1e-8 if tolerance is None else float(tolerance)
    monodromy = monodromy or "auto"
    P, Q = st.parameter, second_parameter
    model = get_model(st.scene.model)
    names = [par.name for par in model.parameters]
    if Q not in names:
        raise ValueError(
            f"second_parameter={Q!r} is not a parameter of model {st.scene.model!r}; allowed: "
            f"{', '.join(sorted(n for n in names if n != P))}"
        )
    if Q == P:
        raise ValueError(f"second_parameter={Q!r} is the first parameter; name another one")
    q0 = float(st.scene.resolved_parameters[Q])
    stop = float(stop)
    lo_end = q0 if start is None else float(start)
    if not (math.isfinite(stop) and math.isfinite(lo_end) and stop != lo_end):
        raise ValueError(f"stop={stop!r}: must be finite and differ from start ({lo_end!r})")
    q_lo, q_hi = min(lo_end, stop), max(lo_end, stop)
    if not q_lo <= q0 <= q_hi:
        raise ValueError(
            f"start={lo_end!r}, stop={stop!r}: the range of {Q} must contain the scene's value "
            f"{q0!r}, where the curve starts (set {Q} in the scene, or widen the range)"
        )
    fam = _Family(st.scene, P, Q, periods=st.periods, rtol=rtol, monodromy=monodromy)
    system = _system(st.kind, event)
    cfg = _Settings(tolerance=tolerance, step=step, max_step=max_step, max_points=max_points)
    # the orbit at the start, its live discrete states, and the touch of a grazing
    first_map = fam.map(q0)
    y, aux = np.asarray(st.y, float), np.asarray(st.aux, float)
    if not isinstance(source, xr.Dataset):
        try:
            orbit = orbit_at(first_map, y, aux, st.p, tolerance=tolerance)
            y, aux = orbit.y, orbit.aux
        except NewtonFailure:
            pass  # the whole defining system may still converge from the guess
    extra = []
    if st.kind == "grazing":
        k, theta, _ = _touch(first_map, y, aux, st.p, event)
        system.event = k
        extra = [theta]
    p_range = None if parameter_range is None else tuple(sorted(parameter_range))
    curve, points, labels, halves = _run(
        fam, system, y, aux, st.p, q0, extra, (lo_end, stop), st.pscale, cfg, p_range, progress
    )
    meta = {
        "tolerance": tolerance,
        "max_points": np.int32(max_points),
        "map_evaluations": np.int32(fam.evaluations),
        "wall_time": time.perf_counter() - wall0,
        "curve_ended": " | ".join(h.ended or "-" for h in halves),
        "curve_unresolved": "; ".join(u for h in halves for u in h.unresolved) or "none",
        "first_parameter_scale": curve.ps,
        "not_detected": "generalised flip, Chenciner (third derivatives), double "
        "Neimark-Sacker, a second contact touching along a grazing orbit",
    }
    return _dataset(points, labels, curve, st, Q, meta)
