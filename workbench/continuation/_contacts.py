"""The contact sequence of a periodic orbit: where each event function crosses in its direction
(contact onsets and ends, for the clearance mechanisms) and by how much it misses or clears
the event surface at each of its turning points (the margins to the next grazing).

An event function ``g_k`` fires where it crosses zero in its direction; its crossings appear or
vanish in pairs where one of its **local extrema** passes through zero: a **grazing** (Nordmark
1991; di Bernardo, Budd, Champneys & Kowalczyk 2008, Sec. 2.5 and Ch. 7). A local maximum below
zero is a free flight that misses the surface by ``-g`` (for the mechanisms: the bearing wall,
``g`` the penetration), a local minimum above zero a lasting contact that stays on by ``g``; a
maximum above zero is the depth of a contact, a minimum below zero that of a free flight inside
a contact: each is a margin to the next change of the sequence. Each extremum is followed
along a branch by its phase, so that a new contact at another phase of a multi-impact orbit,
or changes at two joints, are seen one by one and never cancel in a total.

The sequence is read off the event functions sampled along the orbit over its ``k`` periods
(the solver's dense output at ``samples`` points per period, each extreme sample refined by the
parabola through it and its neighbours: on a smooth extremum an error of order
``(2 pi / samples)^3`` of the event function's range, less at a symmetric one).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "ContactSequence",
    "ambiguous",
    "contact_sequence",
    "match_extrema",
    "nearest_extremum",
]


@dataclass(frozen=True)
class ContactSequence:
    """The contact sequence of one orbit.

    Attributes
    ----------
    span : float
        The orbit's time, ``k`` forcing periods (s).
    directions : ndarray of int
        The direction of each event function (+1 rising, -1 falling, 0 either way).
    crossings : tuple of ndarray
        Per event function, the phases (s after the strobe time) where it crosses zero in its
        direction: where the event fires.
    extrema : tuple of ndarray
        Per event function, rows ``(phase, value, kind)`` of the local extrema of ``g_k`` along
        the orbit, in order of phase: phase in s, value in the event function's units, kind +1
        for a maximum and -1 for a minimum; none for a function that is no switching surface
        (``surface``), and none at a rigid impact (a corner at zero, :func:`_corner`): those
        are no margins to anything.
    scale : ndarray
        Per event function, the range of ``g_k`` along the orbit (event units): the size its
        margins are measured against.
    samples : int
        Samples per forcing period it was read from (0: not said).
    surface : ndarray of bool
        Per event function, whether it is a switching surface
        (:attr:`workbench.solver.Problem.event_surface`; default all).
    """

    span: float
    directions: np.ndarray
    crossings: tuple[np.ndarray, ...]
    extrema: tuple[np.ndarray, ...]
    scale: np.ndarray
    samples: int = 0
    surface: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.surface is None:
            object.__setattr__(self, "surface", np.ones(len(self.crossings), dtype=bool))

    @property
    def counts(self) -> tuple[int, ...]:
        """Crossings per event function over the orbit (as many as the events an integration
        over it locates)."""
        return tuple(int(c.size) for c in self.crossings)

    @property
    def surface_counts(self) -> tuple[int, ...]:
        """Crossings per switching surface (:attr:`surface`): what two orbits' contact sequences
        are compared by. A locator's crossings appear and vanish in pairs with nothing
        happening to the orbit (the impact oscillator's turning points short of the stop)."""
        return tuple(int(c.size) for c, on in zip(self.crossings, self.surface, strict=True) if on)

    def margin(self, k: int) -> np.ndarray:
        """The margins of event function ``k``: ``|value|`` of each local extremum relative to
        the function's range along the orbit (0 at a grazing)."""
        e = self.extrema[k]
        return np.abs(e[:, 1]) / max(float(self.scale[k]), np.finfo(float).tiny)

    def smallest_margin(self) -> tuple[int, float, float]:
        """``(k, phase, value)`` of the local extremum closest to zero relative to its event
        function's range: the next grazing on the way (value in event units)."""
        best, rel = (-1, np.nan, np.nan), np.inf
        for k, e in enumerate(self.extrema):
            if e.shape[0] == 0:
                continue
            r = self.margin(k)
            j = int(np.argmin(r))
            if r[j] < rel:
                rel, best = r[j], (k, float(e[j, 0]), float(e[j, 1]))
        return best


def _vertex(values: np.ndarray, i: int) -> tuple[float, float]:
    """Offset (in samples, within one of i) and value of the vertex of the parabola through the
    periodic samples i - 1, i, i + 1 (the sample itself where the three are collinear)."""
    n = values.size
    a, b, c = values[(i - 1) % n], values[i], values[(i + 1) % n]
    curv = a - 2.0 * b + c
    if curv == 0.0:
        return 0.0, float(b)
    off = min(max(0.5 * (a - c) / curv, -1.0), 1.0)
    return float(off), float(b - 0.25 * (a - c) * off)


#: an extremum whose second differences of the samples next to it exceed those three samples
#: away this many times, and whose value lies within one sample's change of zero, is a corner
#: at zero: a rigid impact (:func:`_corner`)
CORNER = 10.0


def _corner(g: np.ndarray, i: int, kind: int, value: float) -> bool:
    """Whether the extremum at sample i of the periodic samples ``g`` is a corner at zero: the
    event function reaches zero there and turns with a jump of its rate (a rigid impact, where
    the velocity reverses: the impact oscillator's ``x - g`` peaks at exactly 0 at each impact).
    Such an extremum is the event itself, not a margin to a grazing: the vertex of the parabola
    through its samples lies above or below zero with the samples' phase (by up to a few per
    cent of a sample's change, above it where the rates on its two sides differ, r v against
    v), and a sign change from one orbit to the next is no grazing. Read off the samples: the
    second differences that see the corner are of the order of the rate's jump times the
    spacing, those three samples away of the curvature times its square; at a smooth
    extremum (a grazing, a lasting contact's least penetration) they are alike. And its
    sample lies on the near side of zero, or at zero (to 1 % of a sample's change): a compliant
    contact shorter than the spacing (a stiff stop's impact, 0.3 ms against 3.8 ms) is also a
    kink in the samples, but its depth is a margin, and a sample inside it reads it."""
    n = g.size
    d2 = np.array([g[(i + k - 1) % n] - 2.0 * g[(i + k) % n] + g[(i + k + 1) % n]
                   for k in (-3, -1, 0, 1, 3)])  # fmt: skip
    kink = float(np.max(np.abs(d2[1:4])))
    far = float(max(abs(d2[0]), abs(d2[4])))
    step = max(abs(g[i] - g[(i - 1) % n]), abs(g[i] - g[(i + 1) % n]))
    near = kind * g[i] <= 0.01 * step
    return kink > CORNER * far and abs(value) <= step and near


def _extrema(g: np.ndarray) -> list[tuple[int, int]]:
    """``(index, kind)`` of the local extrema of periodic samples (kind +1 maximum, -1 minimum;
    a plateau counts once, at its first sample)."""
    prev, nxt = np.roll(g, 1), np.roll(g, -1)
    out = [(int(i), 1) for i in np.flatnonzero((g > prev) & (g >= nxt))]
    out += [(int(i), -1) for i in np.flatnonzero((g < prev) & (g <= nxt))]
    return sorted(out)


def contact_sequence(
    values: np.ndarray,
    directions: np.ndarray,
    span: float,
    samples: int = 0,
    surface: np.ndarray | None = None,
) -> ContactSequence:
    """The contact sequence from event functions sampled at equal steps over whole periods.

    Parameters
    ----------
    values : ndarray, shape (n, ne)
        ``g_k`` at ``n`` equally spaced times ``j span / n`` after the strobe time (the sample at
        ``span`` is the first again, by periodicity, and is not included).
    directions : ndarray of int, shape (ne,)
        The event functions' directions (+1 rising, -1 falling, 0 either way).
    span : float
        The orbit's time (s).
    samples : int
        Samples per forcing period (recorded with the sequence; 0: not said).
    surface : ndarray of bool, shape (ne,), optional
        Which event functions are switching surfaces (default all): the others get their
        crossings and no extrema.

    Examples
    --------
    >>> t = np.linspace(0, 1, 400, endpoint=False)
    >>> g = np.cos(2 * np.pi * t) - 0.5               # a contact around t = 0
    >>> seq = contact_sequence(np.stack([g, g], axis=1), np.array([1, -1]), 1.0)
    >>> seq.counts, [round(float(v), 6) for v in seq.extrema[0][:, 1]]
    ((1, 1), [0.5, -1.5])
    """
    values = np.asarray(values, dtype=float)
    n, ne = values.shape
    surface = np.ones(ne, bool) if surface is None else np.asarray(surface, dtype=bool)
    dt = span / n
    crossings, extrema, scale = [], [], np.zeros(ne)
    for k in range(ne):
        g = values[:, k]
        scale[k] = float(np.ptp(g)) if n else 0.0
        rows = []
        for i, kind in _extrema(g) if surface[k] else ():
            off, v = _vertex(g, i)
            if _corner(g, i, kind, v):
                continue
            rows.append((((i + off) * dt) % span, v, float(kind)))
        rows.sort()
        e = np.array(rows, dtype=float).reshape(-1, 3)
        phases = []
        for sign in (1.0, -1.0):  # rising, then falling crossings
            if directions[k] * sign < 0:
                continue
            s = sign * g
            up = np.flatnonzero((np.roll(s, 1) <= 0.0) & (s > 0.0))
            a, b = s[(up - 1) % n], s[up]
            phases += list(((up - 1 + (-a / (b - a))) * dt) % span)
            # an excursion through zero between two samples (its vertex beyond zero, its
            # samples on the near side): a maximum above zero rises through it at its left
            # root, a minimum below zero at its right root
            for i, kind in _extrema(s):
                off, v = _vertex(s, i)
                if kind * v > 0.0 and kind * s[i] <= 0.0:
                    phases.append(_rising_root(s, i, off, v) * dt % span)
        crossings.append(np.sort(np.array(phases, dtype=float)))
        extrema.append(e)
    return ContactSequence(
        float(span),
        np.asarray(directions, dtype=np.int64),
        tuple(crossings),
        tuple(extrema),
        scale,
        int(samples),
        surface,
    )


def _rising_root(s: np.ndarray, i: int, off: float, v: float) -> float:
    """The rising root (in samples) of the parabola through samples i - 1, i, i + 1 whose vertex
    (at i + off, value v) lies beyond zero: left of a maximum (v > 0), right of a minimum."""
    n = s.size
    curv = s[(i - 1) % n] - 2.0 * s[i] + s[(i + 1) % n]  # second difference
    half = float(np.sqrt(max(-2.0 * v / curv, 0.0)))
    return i + off - half if curv < 0.0 else i + off + half


def match_extrema(a: np.ndarray, b: np.ndarray, span: float) -> list[tuple[int, int]]:
    """Pairs ``(i, j)`` of the local extrema of one event function on two nearby orbits (rows
    of :attr:`ContactSequence.extrema`), of the same kind and matched by phase: the nearest on
    the circle of length ``span``, each used once, the closest pairs first."""
    if a.shape[0] == 0 or b.shape[0] == 0:
        return []
    d = _circular(a[:, 0][:, None], b[:, 0][None, :], span)
    d[a[:, 2][:, None] != b[:, 2][None, :]] = np.inf
    pairs, used_a, used_b = [], set(), set()
    for flat in np.argsort(d, axis=None):
        i, j = divmod(int(flat), b.shape[0])
        if not np.isfinite(d[i, j]) or i in used_a or j in used_b:
            continue
        pairs.append((i, j))
        used_a.add(i)
        used_b.add(j)
    return sorted(pairs)


#: a pair of matched extrema is told apart from its neighbours where its phase moved by less
#: than this fraction of the distance to the nearest other extremum of its kind on either orbit.
#: Matching by the nearest phase pairs an extremum with its neighbour's partner where the train
#: moved by more than half their spacing; the pair then seems to move by the rest of the
#: spacing, less than half. A quarter flags every such wrong pair up to a move of three
#: quarters of the spacing (the four-bar at 44.5 rad/s: 0.6 of it, read as 0.375)
UNAMBIGUOUS = 0.25


def ambiguous(a: np.ndarray, b: np.ndarray, i: int, j: int, span: float) -> bool:
    """Whether the pair ``(i, j)`` of :func:`match_extrema` may be the wrong one: extrema of
    one kind close together (a journal's rebounds along the bearing's wall, 0.3 ms apart on the
    four-bar at 44 rad/s) drift along the orbit as the parameter moves, and where the pair's
    phases differ by a quarter of their spacing or more (:data:`UNAMBIGUOUS`), matching by the
    nearest phase may have paired one rebound with the next. A sign change read from such a
    pair is no grazing; a shorter step tells them apart (the drift shrinks with the step, the
    spacing does not)."""
    shift = _circular(a[i, 0], b[j, 0], span)
    gaps = [
        _circular(e[n, 0], e[others, 0], span)
        for e, n in ((a, i), (b, j))
        if (others := np.flatnonzero((e[:, 2] == e[n, 2]) & (np.arange(e.shape[0]) != n))).size
    ]
    return bool(gaps) and shift >= UNAMBIGUOUS * min(float(g.min()) for g in gaps)


def nearest_extremum(e: np.ndarray, phase: float, kind: float, span: float) -> int:
    """Row of the extremum of ``kind`` (+1 maximum, -1 minimum) in ``e`` (rows of
    :attr:`ContactSequence.extrema`) nearest to ``phase`` (s) on the circle of length
    ``span`` (s); -1 where there is none."""
    rows = np.flatnonzero(e[:, 2] == kind) if e.shape[0] else np.zeros(0, int)
    if rows.size == 0:
        return -1
    return int(rows[int(np.argmin(_circular(e[rows, 0], phase, span)))])


def _circular(x, y, span: float):
    """Distance (s) between phases x and y (s, arrays broadcast) on the circle of length
    ``span`` (s)."""
    d = np.abs(np.asarray(x) - np.asarray(y)) % span
    return np.minimum(d, span - d)
