"""Grazing labels on oscillators the tests do not contain, drawn at random: where each grazing is
located against its closed form, and whether any label contradicts its multipliers.

Systems (SI units; parameters drawn from ``numpy.random.default_rng(SEED)``):

- ``stop``: the stop oscillator (``stop_oscillator``) with mass 0.5-3 kg, stiffness 0.5-4 N/m,
  damping ratio 0.03-0.2, stop stiffness 10-1000 times the spring's, force 0.1-1 N and a gap
  between the static deflection and the resonance peak; omega continued up through the lower
  grazing and down through the upper one, and from the impacting side down through the lower
  one (the closed form: the linear amplitude
  F / sqrt((k - m w^2)^2 + (c w)^2) equals the gap, ``grazing_amplitude``);
- every fold and period doubling labelled on a stop oscillator's branch is checked against
  an independent piecewise-linear reference (``tests/continuation/_stop_reference``: the flow
  in closed form on each side of the stop): where, within 1e-4 of the label (relative), the
  reference's multiplier passes -1, or its orbits' parameter turns (a fold);
- ``stop-force-gap``: the same draws at a random omega, continued in the force (up) and in the
  gap (down) through the grazing (closed forms: F g / A and A, A the linear amplitude);
- ``stop-curve``: the same draws, the lower grazing located on a branch up in omega and
  continued in the force from 0.8 to 1.25 times the drawn one (``continue_curve``): every point
  of the grazing curve against the closed form (its largest relative error), whether it covers
  the range (down to the least force that grazes at any omega, where it turns), its
  codimension-two points;
- ``impact``: the impact oscillator (``impact_oscillator``, m = k = F = 1) with damping ratio
  0.05-2, restitution 0.3-0.95 and the gap set so that the grazing lies at omega 1.3-3 rad/s;
  omega continued down through it;
- ``impact-curve``: the same draws, the grazing continued in the force as for ``stop-curve``;
- ``impact-flip``: an underdamped impact oscillator (damping ratio 0.02-0.15, restitution
  0.5-0.95, the stop 0.5 m behind to 0.3 m ahead of the rest position) whose period-one orbit
  strikes once per period: an independent reference (``tests/continuation/_impact_reference``:
  the flow between impacts in closed form, the impact map) follows it up in omega to 0.1 rad/s
  past its first flip (a multiplier through -1), and the package's branch from the
  reference's orbit is continued over the same range: every flip of the reference against the
  nearest period doubling labelled (the largest relative error; none where one is missing),
  the labelled ones no flip of the reference explains, and every other label.

Per branch: the located grazing's relative error, the other labels with their critical
multipliers, the labels that contradict them (a fold or branch point with no multiplier within
``MULTIPLIER_TOLERANCE`` of +1, a period doubling with none of -1), the transition and its
note, errors and the CPU time. A grazing is right where it lies within ``RELATIVE`` of the
closed form. Prints one line per branch and a summary; records all of it.

Run: ``python benchmarks/grazing_audit.py --seed 7 --cases 10 --systems stop,stop-curve``
(records in ``benchmarks/records/grazing_audit/``).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
from _results import record, recording  # benchmarks/_results.py: a JSON record per run
from scipy.optimize import brentq, minimize_scalar

from workbench.continuation import branch_bifurcations, continue_curve, continue_orbit
from workbench.continuation._branch import MULTIPLIER_TOLERANCE
from workbench.continuation._newton import NewtonFailure
from workbench.models.stop_oscillator import grazing_amplitude

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "continuation"))
from _impact_reference import ImpactReference  # noqa: E402 (the checks' own references)
from _stop_reference import StopReference, fold  # noqa: E402

#: a grazing within this relative distance of its closed form is right (issue 38, item 8)
RELATIVE = 1e-6
SYSTEMS = ("stop", "stop-force-gap", "stop-curve", "impact", "impact-curve", "impact-flip")


def _roots(f, lo: float, hi: float, n: int = 4000) -> list[float]:
    grid = np.linspace(lo, hi, n)
    v = [f(w) for w in grid]
    return [
        brentq(f, grid[i], grid[i + 1], xtol=1e-15, rtol=1e-15)
        for i in range(n - 1)
        if v[i] * v[i + 1] < 0
    ]


def _contradictions(r, parameter: str) -> list:
    names = r.label.attrs["flag_meanings"].split()
    mu = r.multiplier_real.values + 1j * r.multiplier_imag.values
    bad = []
    for i in np.flatnonzero(r.label.values >= 3):
        kind = names[int(r.label.values[i])]
        m = mu[i][np.isfinite(mu[i])]
        target = {"fold": 1.0, "branch_point": 1.0, "period_doubling": -1.0}.get(kind)
        if target is not None and m.size and np.min(np.abs(m - target)) > MULTIPLIER_TOLERANCE:
            bad.append([kind, float(r[parameter][i]), [str(x) for x in m]])
    return bad


#: a fold or period doubling of a stop oscillator is checked against the reference in this
#: relative window around its label
WINDOW = 1e-4
STOP_NAMES = ("mass", "damping", "stiffness", "stop_stiffness", "gap", "force", "omega")


def _stop_label_checks(r, parameter: str, params: dict) -> list:
    """Every fold and period doubling labelled on a stop oscillator's branch against the
    piecewise-linear reference (``tests/continuation/_stop_reference``: closed-form flow on
    each side of the stop), from the label's orbit: a period doubling where the reference's
    det(M + I) is zero in the window ``(1 +- WINDOW) x`` the label's, a fold where its orbits'
    parameter is extreme (over their strobe x near the label's): ``[kind, label, reference or
    None, relative error or None]``."""
    out = []
    for b in branch_bifurcations(r, parameter):
        if b["type"] not in ("fold", "period_doubling") or not b["resolved"]:
            continue
        i, value = b["index"], b["value"]
        z = np.array([float(r.orbit_x[i]), float(r.orbit_v[i])])
        sign = 1.0 if b["type"] == "period_doubling" else -1.0

        def det(q: float, z=z, sign=sign) -> float:
            ref = StopReference(*[{**params, parameter: q}[n] for n in STOP_NAMES])
            return float(np.linalg.det(ref.jacobian(ref.orbit(z)) + sign * np.eye(2)))

        try:
            if b["type"] == "fold":  # no orbit past it: the extremum of the parameter
                width = WINDOW * max(abs(z[0]), params["gap"])
                exact = fold({**params, parameter: value}, parameter, z, value, width)
                if not abs(exact / value - 1) < WINDOW:
                    raise ValueError("no fold in the window")
            else:
                exact = brentq(
                    det, value * (1 - WINDOW), value * (1 + WINDOW), xtol=1e-15, rtol=1e-15
                )
        except ValueError:  # no sign change in the window, or no orbit: the label is not there
            out.append([b["type"], value, None, None])
            continue
        out.append([b["type"], value, exact, abs(value - exact) / abs(exact)])
    return out


def _branch(
    system: str, case: int, params: dict, model: str, parameter: str, start, stop, exact, then=None
):
    scene = {
        "model": {"name": model},
        "parameters": {**params, parameter: start},
        "run": {"transient_cycles": 300},
    }
    row = {"system": system, "case": case, "parameter": parameter, "start": start, "stop": stop}
    row.update(exact=exact, parameters=params)
    t0 = time.process_time()
    try:
        r = continue_orbit(scene, parameter, stop=stop)
    except NewtonFailure as exc:  # no period-1 orbit where the transient ended: said clearly
        row["start_failed"] = str(exc)
        row["cpu"] = time.process_time() - t0
        return row
    except Exception as exc:  # a traceback is a finding: recorded, not raised
        row["error"] = f"{type(exc).__name__}: {exc}"
        row["cpu"] = time.process_time() - t0
        return row
    found = branch_bifurcations(r, parameter)
    grazings = [b for b in found if b["type"] == "grazing" and b["resolved"]]
    first = min(grazings, key=lambda b: abs(b["value"] - start)) if grazings else None
    row["relative_error"] = abs(first["value"] - exact) / exact if first else None
    row["transition"] = first.get("transition") if first else None
    row["labels"] = [
        [b["type"], b["value"], bool(b["resolved"]), str(b["critical"])] for b in found
    ]
    row["contradictions"] = _contradictions(r, parameter)
    if model == "stop_oscillator":
        row["label_checks"] = _stop_label_checks(r, parameter, {**params, parameter: start})
    row["notes"] = r.attrs.get("bifurcation_notes", "")
    row["ended"] = r.attrs.get("branch_ended", "")
    row["points"] = int(r.sizes["point"])
    # contacts per period of the first orbit: a branch that starts on an impacting orbit (one
    # that coexists with the non-impacting one) can pass the grazing value without a grazing
    row["start_crossings"] = int(np.sum(r.crossings_per_orbit.values[0]))
    if then is not None and first is not None:
        then(r, row)
    row["cpu"] = time.process_time() - t0
    return row


def _stop_draw(rng) -> dict:
    m, k = float(rng.uniform(0.5, 3)), float(rng.uniform(0.5, 4))
    zeta = float(rng.uniform(0.03, 0.2))
    c, ks, F = 2 * zeta * math.sqrt(k * m), k * float(10 ** rng.uniform(1, 3)), rng.uniform(0.1, 1)
    return {"mass": m, "damping": c, "stiffness": k, "stop_stiffness": ks, "force": float(F)}


def _amplitude(p: dict, w: float) -> float:
    return grazing_amplitude({**p, "gap": 1.0, "omega": w})


def _stop_with_gap(rng) -> tuple[dict, list[float]]:
    """A stop oscillator drawn with its gap between the static deflection and the resonance
    peak, and the omegas where its linear orbit grazes (the closed form's roots)."""
    p = _stop_draw(rng)
    w0 = math.sqrt(p["stiffness"] / p["mass"])
    peak = max(_amplitude(p, w) for w in np.linspace(0.3 * w0, 2 * w0, 400))
    static = p["force"] / p["stiffness"] * 1.05
    p["gap"] = float(static + rng.uniform(0.2, 0.8) * (peak - static))
    return p, _roots(lambda w: _amplitude(p, w) - p["gap"], 0.2 * w0, 3 * w0, 2000)


def stop_rows(rng, case: int):
    p, g = _stop_with_gap(rng)
    yield _branch("stop", case, p, "stop_oscillator", "omega", g[0] * 0.9, g[0] * 1.05, g[0])
    yield _branch("stop", case, p, "stop_oscillator", "omega", g[-1] * 1.1, g[-1] * 0.97, g[-1])
    # from the impacting side out of the contact: down through the lower grazing
    yield _branch("stop", case, p, "stop_oscillator", "omega", g[0] * 1.01, g[0] * 0.95, g[0])


def stop_force_gap_rows(rng, case: int):
    p = _stop_draw(rng)
    p["omega"] = math.sqrt(p["stiffness"] / p["mass"]) * float(rng.uniform(0.4, 1.6))
    a = _amplitude(p, p["omega"])
    fg = p["force"] / a  # the force at which the amplitude is the gap 1 m
    yield _branch(
        "stop-force-gap", case, {**p, "gap": 1.0}, "stop_oscillator", "force", 0.8 * fg,
        1.1 * fg, fg,
    )  # fmt: skip
    yield _branch("stop-force-gap", case, p, "stop_oscillator", "gap", 1.3 * a, 0.9 * a, a)


def _force_curve(p: dict):
    """Continue a branch's first grazing in the force, 0.8 .. 1.25 x ``p["force"]``, and put
    each point of the curve against the closed form (the linear amplitude at its omega and
    force equals the gap)."""
    lo, hi = 0.8 * p["force"], 1.25 * p["force"]

    def check(r, row) -> None:
        try:
            c = continue_curve(r, "force", start=lo, stop=hi, kind="grazing")
        except Exception as exc:  # a failed curve is a finding: recorded
            row["curve_error"] = f"{type(exc).__name__}: {exc}"
            return
        errors = [
            abs(grazing_amplitude({**p, "force": float(f), "omega": float(w)}) - p["gap"])
            / p["gap"]
            for w, f in zip(c.omega.values, c.force.values, strict=True)
        ]
        names = c.label.attrs["flag_meanings"].split()
        row["curve_points"] = int(c.sizes["curve_point"])
        row["curve_relative_error"] = float(max(errors))
        row["curve_force_range"] = [float(c.force.min()), float(c.force.max())]
        # below the least force that reaches the gap at any omega there is no grazing: the
        # curve turns there (F = g |k - m w^2 + i c w|, least near resonance)
        least = minimize_scalar(
            lambda w: p["gap"] * abs(complex(p["stiffness"] - p["mass"] * w * w, p["damping"] * w)),
            bounds=(0.0, 3 * math.sqrt(p["stiffness"] / p["mass"])),
            method="bounded",
            options={"xatol": 1e-12},
        ).fun
        row["least_force"] = float(least)
        row["curve_covered"] = bool(
            c.force.min() <= max(lo, least) * (1 + RELATIVE) and c.force.max() >= hi * (1 - 1e-9)
        )
        row["curve_special"] = [names[int(v)] for v in c.special_label.values]
        row["curve_ended"] = c.attrs.get("curve_ended", "")

    return check


def stop_curve_rows(rng, case: int):
    p, g = _stop_with_gap(rng)
    yield _branch(
        "stop-curve", case, p, "stop_oscillator", "omega", g[0] * 0.9, g[0] * 1.05, g[0],
        then=_force_curve(p),
    )  # fmt: skip


def _impact_with_gap(rng) -> tuple[dict, float]:
    """An impact oscillator drawn with its gap, and the omega where its linear orbit grazes
    (the closed form's upper root)."""
    zeta = float(10 ** rng.uniform(-1.3, 0.3))
    p = {"mass": 1.0, "damping": 2 * zeta, "stiffness": 1.0, "force": 1.0}
    p["restitution"] = float(rng.uniform(0.3, 0.95))
    p["gap"] = _amplitude(p, float(rng.uniform(1.3, 3.0)))
    return p, max(_roots(lambda w: _amplitude(p, w) - p["gap"], 0.2, 4.0))


def impact_rows(rng, case: int):
    p, wg = _impact_with_gap(rng)
    yield _branch("impact", case, p, "impact_oscillator", "omega", wg * 1.15, wg * 0.95, wg)


def impact_curve_rows(rng, case: int):
    p, wg = _impact_with_gap(rng)
    yield _branch(
        "impact-curve", case, p, "impact_oscillator", "omega", wg * 1.15, wg * 0.95, wg,
        then=_force_curve(p),
    )  # fmt: skip


def _reference_flips(c: float, g: float, r: float):
    """From the first omega (1.0, 1.1, ...) with a stable period-one impacting orbit, that
    orbit followed up in omega (Newton from the last, steps of 0.02 rad/s, then 0.005 past the
    first flip) to 0.1 rad/s past its first flip: ``(w_stable, its strobe state, [every omega
    where det(J + I) changes sign], the end of the range)``; None where there is no stable
    orbit up to 4 rad/s, or the orbit is lost or a free swing reaches the stop (another
    bifurcation) before a flip. Past the first flip the range ends where a swing reaches the
    stop."""
    start = None
    for w in np.arange(1.0, 4.0, 0.1):
        ref = ImpactReference(c, g, r, float(w))
        for z in ref.period_one():
            if np.max(np.abs(np.linalg.eigvals(ref.jacobian(z)))) < 0.95:
                start = (float(w), z)
                break
        if start:
            break
    if start is None:
        return None
    w, z = start
    state = ImpactReference(c, g, r, w).strobe_state(z)

    def det(w: float, z) -> tuple[float, np.ndarray]:
        ref = ImpactReference(c, g, r, w)
        z = ref.orbit(z)
        return float(np.linalg.det(ref.jacobian(z) + np.eye(2))), z

    d0, _ = det(w, z)
    flips, end = [], 8.0
    while w < end:
        step = 0.005 if flips else 0.02
        try:
            d1, z1 = det(w + step, z)
        except ValueError:
            break
        if ImpactReference(c, g, r, w + step).margin(z1) > 0:
            break  # a free swing reaches the stop: another bifurcation
        if np.sign(d1) != np.sign(d0):
            q = brentq(lambda q, z=z: det(q, z)[0], w, w + step, xtol=1e-14, rtol=1e-15)
            flips.append(q)
            end = min(end, flips[0] + 0.1)
        w, z, d0 = w + step, z1, d1
    return (start[0], state, flips, min(w, end)) if flips else None


def impact_flip_rows(rng, case: int):
    zeta = float(rng.uniform(0.02, 0.15))
    p = {"mass": 1.0, "damping": 2 * zeta, "stiffness": 1.0, "force": 1.0}
    p["restitution"] = float(rng.uniform(0.5, 0.95))
    p["gap"] = float(rng.uniform(-0.5, 0.3))
    p["x0"] = min(0.0, p["gap"] - 0.3)
    row = {"system": "impact-flip", "case": case, "parameter": "omega", "parameters": dict(p)}
    t0 = time.process_time()
    found = _reference_flips(p["damping"], p["gap"], p["restitution"])
    if found is None:
        row["start_failed"] = "the reference finds no flip of a stable period-one orbit"
        row["cpu"] = time.process_time() - t0
        yield row
        return
    w_start, state, exact, stop = found
    row.update(start=w_start, stop=stop, exact=exact[0], reference_flips=exact)
    scene = {"model": {"name": "impact_oscillator"}, "parameters": {**p, "omega": w_start}}
    try:
        r = continue_orbit(scene, "omega", stop=stop, state=state)
    except Exception as exc:  # a traceback is a finding: recorded, not raised
        row["error"] = f"{type(exc).__name__}: {exc}"
        row["cpu"] = time.process_time() - t0
        yield row
        return
    labels = branch_bifurcations(r, "omega")
    flips = [b["value"] for b in labels if b["type"] == "period_doubling" and b["resolved"]]
    # every reference flip against the nearest label, and labels no reference flip explains
    errors = [min((abs(f - q) / q for f in flips), default=math.inf) for q in exact]
    row["relative_error"] = max(errors) if flips else None
    row["unexplained_flips"] = [f for f in flips if min(abs(f - q) / q for q in exact) > RELATIVE]
    row["labels"] = [
        [b["type"], b["value"], bool(b["resolved"]), str(b["critical"])] for b in labels
    ]
    row["contradictions"] = _contradictions(r, "omega")
    row["ended"] = r.attrs.get("branch_ended", "")
    row["points"] = int(r.sizes["point"])
    row["start_crossings"] = int(np.sum(r.crossings_per_orbit.values[0]))
    row["cpu"] = time.process_time() - t0
    yield row


def _checks_text(row: dict) -> str:
    if not row.get("label_checks"):
        return ""
    return (
        " reference "
        + ", ".join(
            f"{c[0]} {'none' if c[3] is None else f'{c[3]:.1e}'}" for c in row["label_checks"]
        )
        + " "
    )


def _curve_text(row: dict) -> str:
    if "curve_error" in row:
        return f"curve failed: {row['curve_error'][:80]}"
    if "curve_relative_error" not in row:
        return ""
    return (
        f"curve {row['curve_points']} points, error {row['curve_relative_error']:.1e}, force "
        f"{row['curve_force_range'][0]:.4g}..{row['curve_force_range'][1]:.4g}, special "
        f"{row['curve_special']}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--cases", type=int, default=10)
    ap.add_argument("--systems", default=",".join(SYSTEMS))
    args = ap.parse_args()
    systems = args.systems.split(",")
    for name in systems:
        if name not in SYSTEMS:
            raise SystemExit(f"--systems: {name!r} is not one of {', '.join(SYSTEMS)}")
    rows = []
    for name in systems:
        rng = np.random.default_rng(args.seed)
        make = {
            "stop": stop_rows, "stop-force-gap": stop_force_gap_rows,
            "stop-curve": stop_curve_rows, "impact": impact_rows,
            "impact-curve": impact_curve_rows, "impact-flip": impact_flip_rows,
        }  # fmt: skip
        for case in range(args.cases):
            for row in make[name](rng, case):
                rows.append(row)
                err = row.get("relative_error")
                print(
                    f"{row['system']:15s} {case:2d} {row['parameter']:6s} "
                    f"{'flip' if name == 'impact-flip' else 'grazing'} "
                    f"{'none' if err is None else f'{err:.1e}'}  "
                    f"{row.get('transition') or ''}  "
                    f"labels {[(b[0], round(b[1], 7)) for b in row.get('labels', [])]}  "
                    f"contradictions {row.get('contradictions', [])} {row.get('error', '')}"
                    f"{_checks_text(row)}"
                    f"{'no start: ' + row['start_failed'][:60] if 'start_failed' in row else ''}  "
                    f"{_curve_text(row)}"
                    f"{row['cpu']:.1f} s",
                    flush=True,
                )
    right = sum(
        r.get("relative_error") is not None and r["relative_error"] <= RELATIVE for r in rows
    )
    bad = sum(bool(r.get("contradictions")) for r in rows)
    unexplained = sum(bool(r.get("unexplained_flips")) for r in rows)
    checks = [c for r in rows for c in r.get("label_checks", [])]
    misplaced = [c for c in checks if c[3] is None or c[3] > RELATIVE]
    if checks:
        print(
            f"{len(checks)} folds and period doublings of stop oscillators against the "
            f"piecewise-linear reference: {len(checks) - len(misplaced)} within {RELATIVE:g}, "
            f"misplaced {misplaced}"
        )
    errors = sum("error" in r for r in rows)
    unstarted = sum("start_failed" in r for r in rows)
    missed = [r for r in rows if "points" in r and r["relative_error"] is None]
    impacting = sum(r["start_crossings"] > 0 for r in missed)
    curves = [r for r in rows if "curve_relative_error" in r or "curve_error" in r]
    curves_right = sum(r.get("curve_relative_error", math.inf) <= RELATIVE for r in curves)
    if curves:
        print(
            f"{len(curves)} grazing curves: {curves_right} within {RELATIVE:g} of the closed "
            f"form at every point, {sum(r.get('curve_covered', False) for r in curves)} "
            f"covering their range (down to the least grazing force where it lies in it), "
            f"{sum('curve_error' in r for r in curves)} failed"
        )
    print(
        f"{len(rows)} branches: {unstarted} found no period-1 orbit to start from; of the "
        f"others {right} have the grazing (impact-flip: every flip) within {RELATIVE:g} of its "
        f"closed form (impact-flip: the reference), "
        f"{len(missed)} no grazing ({impacting} of them start on an impacting orbit, which "
        f"coexists with the non-impacting one there), {bad} a label their multipliers "
        f"contradict, {unexplained} a period doubling the reference does not have, {errors} an "
        "error"
    )
    record(
        {
            "seed": args.seed, "cases": args.cases, "systems": systems, "branches": len(rows),
            "grazing_right": right, "contradicted": bad, "errors": errors,
            "unexplained_flips": unexplained, "stop_labels_checked": len(checks),
            "stop_labels_misplaced": len(misplaced),
            "start_failed": unstarted, "no_grazing": len(missed),
            "no_grazing_impacting_start": impacting, "curves": len(curves),
            "curves_right": curves_right, "rows": rows,
        }
    )  # fmt: skip


if __name__ == "__main__":
    with recording(__file__):
        main()
