"""The REPORT section of a study's route to chaos (:mod:`workbench.study._route`), written from
the numbers of its ``summary.json`` only."""

from __future__ import annotations

import math

__all__ = ["route_section"]


def _v(x: float, param: str) -> str:
    """A parameter value as the report shows it (omega in units of pi, clearance in mm)."""
    if param == "omega":
        return f"{x / math.pi:.4g} pi"
    if param == "clearance":
        return f"{x * 1e3:.4g} mm"
    return f"{x:.4g}"


def _num(x) -> str:
    return "–" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.3g}"


def _mu(z: list[float]) -> str:
    re, im = z
    return (
        f"{re:+.4f}" if abs(im) < 1e-9 else f"{re:+.4f}{im:+.4f}i (|mu| {math.hypot(re, im):.4f})"
    )


def route_section(r: dict) -> list[str]:
    """Markdown lines: what the continued sweeps, the periodic branch and the indicators say."""
    if not r or r.get("status") != "computed":
        return []
    p = r["parameter"]
    values = r["values"]
    cycles, transient = r["cycles"]
    up, down = r["directions"]["up"], r["directions"]["down"]
    lines = [
        f"**Beyond the paper: how the motion becomes chaotic.** The sweep over {p} continued "
        f"both ways (`workbench.continuation.continued_sweep`: each point starts from the state "
        f"its neighbour settled to, {transient} transient + {cycles} recorded cycles per "
        f"point; {r['chained_seams']} seam(s) chained; workers' CPU "
        f"{r['cpu_time_continued_sweep'] / 60:.1f} min, "
        f"{r['wall_time']['continued_sweep'] / 60:.1f} min wall).",
        "",
    ]
    b = r.get("branch")
    if b:
        lines += _branch_lines(b, p)
    if r.get("end"):
        lines += _end_lines(r["end"], p)
    h = r["hysteresis"]
    if h["values"]:
        shown = ", ".join(_v(v, p) for v in h["values"])
        lines += [
            f"*Hysteresis*: the two directions settle on different attractors at "
            f"{len(h['values'])} of {len(values)} values ({shown}; mean nearest-sample distance "
            f"above {h['tolerance']:g} c plus twice the samples' own spacing).",
            "",
        ]
    else:
        lines += [
            f"*Hysteresis*: none; at every value the two directions reach the same attractor "
            f"(mean nearest-sample distance within {h['tolerance']:g} c plus twice the "
            "samples' own spacing).",
            "",
        ]
    exps = {e["value"]: e for e in r.get("exponents", [])}
    head = f"| {p} | period up / down | strobe spread / c, up / down | 0-1 K up / down |"
    head += " largest Lyapunov exponent [1/s] |" if exps else ""
    lines += [head, "|---|---|---|---|" + ("---|" if exps else "")]
    for i, v in enumerate(values):
        per = "/".join(str(x) if x > 0 else "none" for x in (up["period"][i], down["period"][i]))
        row = (
            f"| {_v(v, p)} | {per} | {_num(up['spread'][i])} / {_num(down['spread'][i])} | "
            f"{_num(up['K'][i])} / {_num(down['K'][i])} |"
        )
        if exps:
            e = exps.get(v)
            if e is None:
                row += " |"
            elif e.get("bound"):
                row += f" <= {e['lle']:.3g} (Floquet bound) |"
            elif "lle" in e:
                how = {"floquet": " (Floquet)"}.get(e.get("method", "copies"), "")
                row += f" {e['lle']:.3g} +- {e['stderr']:.2g}{how}{_unconverged(e)} |"
            else:
                row += " failed |"
        lines.append(row)
    lines += ["", *_agreement(r), ""]
    return lines


def _unconverged(e: dict) -> str:
    """A trajectory exponent's ``note`` (one line per condition its estimator did not meet, or
    why Newton found no orbit first) as a table cell's suffix: such a value is not converged or
    not what the route asked for. Empty for a Floquet value and for a clean estimate."""
    if e.get("method", "copies") == "floquet" or not e.get("note"):
        return ""
    lines = e["note"].splitlines()
    failed = [line for line in lines if "not run" not in line]
    skipped = [line.split(":")[0] for line in lines if "not run" in line]
    return (" (flagged: " + "; ".join(failed) + ")" if failed else "") + (
        " (not checked: " + ", ".join(skipped) + ")" if skipped else ""
    )


def _branch_lines(b: dict, p: str) -> list[str]:
    stable = [v for v, s in zip(b["values"], b["stable"], strict=True) if s]
    lines = [
        f"*The periodic orbit* (`workbench.continuation.continue_orbit`, shooting with the "
        f"monodromy matrix by {b['monodromy']}, pseudo-arclength from {_v(b['start'], p)} "
        f"towards {_v(b['stop'], p)}; {b['map_evaluations']} map evaluations; ended: "
        f"{b['ended']}): stable at "
        + (f"{_v(min(stable), p)} .. {_v(max(stable), p)}" if stable else "no point")
        + f" of the {len(b['values'])} continued orbits.",
        "",
    ]
    if b["bifurcations"]:
        lines += [
            f"| bifurcation | {p} | critical multiplier | largest multipliers there | stable "
            "before / after | events per cycle before / after |",
            "|---|---|---|---|---|---|",
        ]
        for f in b["bifurcations"]:
            mus = ", ".join(_mu(z) for z in f["multipliers"][:3])
            lines.append(
                f"| {f['type'].replace('_', ' ')} | {_v(f['value'], p)} | {_mu(f['critical'])} "
                f"| {mus} | {'yes' if f['stable_before'] else 'no'} / "
                f"{'yes' if f['stable_after'] else 'no'} | {f['events_before']:g} / "
                f"{f['events_after']:g} |"
            )
        lines.append("")
    loss = next(
        (f for f in b["bifurcations"] if f["stable_before"] and not f["stable_after"]), None
    )
    if loss:
        lines += [
            f"Where and how the periodic motion ends: the orbit loses stability at "
            f"{p} = {_v(loss['value'], p)} by a **{loss['type'].replace('_', ' ')}** (critical "
            f"multiplier {_mu(loss['critical'])}).",
            "",
        ]
    else:
        lines += [
            "The periodic orbit does not lose stability on the continued range "
            f"(largest |multiplier| {max(b['largest_modulus']):.3g}).",
            "",
        ]
    return lines


def _agreement(r: dict) -> list[str]:
    """How the branch, the strobe periods, the 0-1 test and the exponents agree."""
    p = r["parameter"]
    up, down = r["directions"]["up"], r["directions"]["down"]
    values = r["values"]
    periodic = [
        v for v, a, b in zip(values, up["period"], down["period"], strict=True) if a == b == 1
    ]
    chaotic = [
        v
        for v, a, b in zip(values, up["K"], down["K"], strict=True)
        if a is not None and b is not None and math.isfinite(a) and a > 0.5 and b > 0.5
    ]
    tested = any(k is not None and math.isfinite(k) for k in up["K"] + down["K"])
    text = [
        f"Agreement: both directions are period-1 at {len(periodic)} of {len(values)} values"
        + (f" ({_v(min(periodic), p)} .. {_v(max(periodic), p)})" if periodic else "")
        + (
            f"; the 0-1 test gives K > 0.5 both ways at {len(chaotic)}"
            + (f" ({_v(min(chaotic), p)} .. {_v(max(chaotic), p)})" if chaotic else "")
            if tested
            else f"; no 0-1 test (it needs 100 strobe samples, these record {r['cycles'][0]})"
        )
        + "."
    ]
    b = r.get("branch")
    if b:
        inside = [v for v in periodic if b["start"] <= v <= max(b["values"])]
        stable_at = {v: s for v, s in zip(b["values"], b["stable"], strict=True)}
        if inside and stable_at:
            near = [stable_at[min(stable_at, key=lambda w, v=v: abs(w - v))] for v in inside]
            text.append(
                f"Where the sweeps are period-1 inside the branch's range ({len(inside)} values) "
                f"the nearest continued orbit is stable at {sum(near)}."
            )
    exps = [e for e in r.get("exponents", []) if "lle" in e]
    if exps:
        pos = [e for e in exps if not e.get("bound") and e["lle"] > 2 * e["stderr"]]
        neg = [e for e in exps if e["lle"] < 0 and (e.get("bound") or e["lle"] < -2 * e["stderr"])]
        floq = sum(e.get("method") == "floquet" for e in exps)
        text.append(
            f"The largest exponent ({len(exps)} values: {floq} from the Floquet multipliers of "
            f"the period-k orbit where the strobe is periodic, {len(exps) - floq} by the "
            f"two-trajectory method) is positive beyond two errors at "
            + (", ".join(_v(e["value"], p) for e in pos) or "none")
            + ", negative at "
            + (", ".join(_v(e["value"], p) for e in neg) or "none")
            + "."
        )
    return [" ".join(text)]


def _end_lines(e: dict, p: str) -> list[str]:
    """Where and how the periodic motion ends (:mod:`workbench.study._route_end`)."""
    if e.get("status") != "computed":
        return [f"*Where the periodic motion ends*: not computed ({e.get('reason', '')}).", ""]
    lo, hi = e["bracket"]
    step = (hi - lo) / max(len(e["values"]) - 1, 1)
    up = e["last_periodic_up"]
    fup, fdown = e["directions"]["up"], e["directions"]["down"]
    first_up = next((v for v, k in zip(e["values"], fup["period"], strict=True) if k != 1), None)
    # coming down: the first period-1 value from the top, and where the directions differ
    down = next(
        (v for v, k in zip(e["values"][::-1], fdown["period"][::-1], strict=True) if k == 1),
        None,
    )
    differ = [
        (v, a, b)
        for v, a, b in zip(e["values"], fup["period"], fdown["period"], strict=True)
        if a != b
    ]
    kind = {0: "none", 1: "1"}
    lines = [
        f"*Where the periodic motion ends* (the continued sweep again at {len(e['values'])} values "
        f"between {_v(lo, p)} and {_v(hi, p)}, both ways, {e['cpu_time'] / 60:.1f} min of "
        "workers' CPU): going up the strobe is period-1 up to "
        + (_v(up, p) if up is not None else "none of them")
        + (f" and not at {_v(first_up, p)}" if first_up is not None else "")
        + "; coming down it is period-1 first at "
        + (_v(down, p) if down is not None else "none of them")
        + (
            f" (the same value: no hysteresis at the end, to the refined step {_v(step, p)})."
            if up is not None and up == down and not differ
            else " (the two directions differ: hysteresis"
            + (
                "; the strobe's period up / down is "
                + ", ".join(
                    f"{kind.get(a, a)} / {kind.get(b, b)} at {_v(v, p)}" for v, a, b in differ
                )
                if differ
                else ""
            )
            + ")."
        ),
        "",
    ]
    lines += _orbit_lines(e.get("last_orbit"), p) + _other_contact_lines(e, p)
    b = e.get("branch")
    if b is None:
        lines += [f"The orbit could not be continued: {e.get('branch_error', '')}", ""]
        return lines
    loss = next(
        (f for f in b["bifurcations"] if f["stable_before"] and not f["stable_after"]), None
    )
    # resolved grazings only (an unresolved one is a bracket, not a label), along the branch;
    # the route's lift-off is the last of them, the nearest to the impacting orbits
    grazes = sorted(
        (f for f in b["bifurcations"] if f["type"] == "grazing" and f.get("resolved", True)),
        key=lambda f: f["value"],
    )
    graze = grazes[-1] if grazes else None
    low = [x for x in b["smallest_event"] if math.isfinite(x)]
    span = abs(b["values"][-1] - b["values"][0]) or 1.0
    failed = e.get("failed_starts") or []
    text = (
        f"The period-1 orbit continued from {_v(b['start'], p)} (from the state the refined "
        "sweep settled to"
        + (
            f"; Newton did not converge from the {len(failed)} periodic value(s) above it"
            if failed
            else ""
        )
        + f"; {len(b['values'])} points, {b['map_evaluations']} map evaluations) "
        f"reaches {_v(max(b['values']), p)} and ends there: {b['ended']}."
    )
    if low:
        text += (
            f" The smallest event value along the orbit (the mechanisms: the smallest "
            f"penetration of a joint in lasting contact) falls from {low[0]:.3g} to "
            f"{low[-1]:.3g} m"
            + (
                f"; {'a grazing is' if len(grazes) == 1 else 'grazings are'} labelled at "
                + " and ".join(_v(g["value"], p) for g in grazes)
                + "."
                if grazes
                else "."
            )
        )
    if loss and graze and abs(loss["value"] - graze["value"]) < 0.01 * span:
        i = min(range(len(b["values"])), key=lambda k: abs(b["values"][k] - loss["value"]))
        before = b["largest_modulus"][max(i - 1, 0)]
        after = max(b["largest_modulus"][i:])
        text += (
            f" Its largest |multiplier| stays within {min(b['largest_modulus'][:i]):.3g}-"
            f"{max(b['largest_modulus'][: max(i, 1)]):.3g} up to {_v(loss['value'], p)}, where "
            f"it jumps from {before:.3g} to {after:.3g} (labelled a "
            f"{loss['type'].replace('_', ' ')}) "
            f"within {_v(abs(graze['value'] - loss['value']), p)} of the lift-off: the map's "
            "derivative grows without bound as a contact grazes (with a rigid stop the "
            "square-root singularity of grazing, Nordmark 1991; here a compliant contact's "
            "lift-off), so **the lasting-contact orbit ends at the grazing, where a contact "
            "lifts off**, not at a smooth bifurcation "
            "(no fold, period doubling or Neimark-Sacker before it)."
        )
    elif loss:
        text += (
            f" Its largest |multiplier| stays within {min(b['largest_modulus']):.3g}-"
            f"{max(b['largest_modulus']):.3g}; it loses stability at {_v(loss['value'], p)} by a "
            f"**{loss['type'].replace('_', ' ')}** (critical multiplier {_mu(loss['critical'])})."
        )
    else:
        text += (
            f" Its largest |multiplier| stays within {min(b['largest_modulus']):.3g}-"
            f"{max(b['largest_modulus']):.3g}: **no multiplier leaves the unit circle** (no fold, "
            "period doubling or Neimark-Sacker)"
            + (
                ", and the lasting contact approaches lift-off (a grazing)."
                if low and low[-1] < low[0]
                else "."
            )
        )
    lines += [text, ""]
    o = e.get("last_orbit") or {}
    if graze and o.get("smallest_event", 0.0) < 0 and up is not None and up > graze["value"]:
        k_next = next(
            (k for v, k in zip(e["values"], fup["K"], strict=True) if v == first_up), None
        )
        lines += [
            f"**The route**: lasting contact up to the grazing at {_v(graze['value'], p)}; "
            f"then period-1 motion with impacts (the orbit at {_v(o['value'], p)}: "
            f"{o['events_per_period']:g} contact events per cycle, largest |multiplier| "
            f"{o['largest_modulus']:.3g}) up to {_v(up, p)}; "
            + (
                f"no period from {_v(first_up, p)} on (0-1 test K = {k_next:.3g})."
                if first_up is not None and k_next is not None
                else "no period above it."
            ),
            "",
        ]
    held = e.get("held") or []
    if held:
        cells = "; ".join(
            f"x{h['factor']:g} ({', '.join(f'{a:.3g}' for a in h['held'])} m s-1): "
            + (f"{h['largest_modulus']:.3g}" if math.isfinite(h["largest_modulus"]) else "no orbit")
            for h in held
        )
        lines += [
            f"*History*: the orbit at {_v(b['start'], p)} holds each contact's onset velocity "
            "(the Lankarani-Nikravesh damping's, held while the contact lasts). Found again with "
            f"those velocities scaled, its largest |multiplier| is {cells}: the lasting-contact "
            "orbit is a family, one per onset velocity, and how stable the periodic motion is "
            "depends on the impact that began the contact, not on the parameter alone.",
            "",
        ]
    return lines


def _orbit_lines(o: dict | None, p: str, law: str = "") -> list[str]:
    """The period-1 orbit Newton found at the end of the refined sweep's period-1 values going
    up (``law``: the other contact law it was found under)."""
    if not o:
        return []
    if "error" in o:
        return [
            f"At {_v(o['value'], p)}{' under ' + law if law else ''} Newton finds no period-1 "
            f"orbit ({o['error']}).",
            "",
        ]
    lifted = math.isfinite(o["smallest_event"]) and o["smallest_event"] < 0
    rtol = f", at rtol {o['rtol']:g}" if "rtol" in o else ""
    return [
        (f"Under {law}, the" if law else "The")
        + f" period-1 orbit Newton finds at {_v(o['value'], p)} (from the refined sweep's "
        f"state{rtol}) has {o['events_per_period']:g} events per cycle, largest |multiplier| "
        f"{o['largest_modulus']:.3g} and smallest event value {o['smallest_event']:.3g} m"
        + (
            ": a contact lifts off and closes again every cycle there (an impacting orbit)."
            if lifted
            else ": its contacts last through the cycle."
        ),
        "",
    ]


#: how the report names a scene's contact law (``[effects] contact``)
CONTACT_NAMES = {"lankarani_nikravesh": "Lankarani-Nikravesh", "hunt_crossley": "Hunt-Crossley"}


def _other_contact_lines(e: dict, p: str) -> list[str]:
    """Whether the end survives another contact law (``[route] end_other_contact``): the
    highest period-1 value going up (none above it in the refined range) under each law, the
    same within half the refined step or not, and the other law's values below its end where
    the strobe is not period-1."""
    o = e.get("other_contact")
    if not o:
        return []
    name = CONTACT_NAMES.get(o["contact"], o["contact"])
    step = (e["bracket"][1] - e["bracket"][0]) / max(len(e["values"]) - 1, 1)
    mine, theirs = e.get("highest_periodic_up", e["last_periodic_up"]), o["highest_periodic_up"]
    settings = ", ".join(f"{k} = {v:g}" for k, v in o["parameters"].items())
    head = (
        f"*Without the contact's memory* (the refined sweep again under the {name} law"
        + (f", {settings}" if settings else "")
        + f"; {o['cpu_time'] / 60:.1f} min of workers' CPU): "
    )
    if theirs is None:
        return [head + "the strobe is period-1 at none of the values going up: the periodic "
                "motion does not reach this range under that law.", ""]  # fmt: skip
    gaps = [
        v for v, k in zip(o["values"], o["directions"]["up"]["period"], strict=True)
        if k != 1 and v < theirs
    ]  # fmt: skip
    same = mine is not None and abs(theirs - mine) <= step / 2
    text = (
        head
        + f"going up the strobe is period-1 last at {_v(theirs, p)}"
        + (f" (not at {', '.join(_v(v, p) for v in gaps)} below it)" if gaps else "")
        + f", against {_v(mine, p) if mine is not None else 'none'} here. "
        + (
            f"**The end of periodic motion survives the change of contact law** (the same "
            f"value, to the refined step {_v(step, p)})."
            if same
            else f"**The end of periodic motion moves with the contact law**, by "
            f"{_v(theirs - mine, p)}."
            if mine is not None
            else "**Periodic motion reaches this range only without the memory.**"
        )
    )
    return [text, ""] + _orbit_lines(o.get("last_orbit"), p, name)
