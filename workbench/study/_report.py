"""``studies/REPORT.md``: the paper's numbers and conclusions beside ours, generated from the
``summary.json`` files that :func:`workbench.study.run_study` writes."""

from __future__ import annotations

import json
import math
import os
import platform
from datetime import UTC, datetime
from pathlib import Path

from workbench.archive import write_text_atomic
from workbench.study._route_report import route_section
from workbench.study._spec import available_studies, report_path

__all__ = ["write_report"]

_CAUSES = """\
## Known causes of difference

1. **Reconstructed geometry.** The paper's tables were lost in extraction; L71, L72, beta, L8,
   the rocker pivot O6, the slider offset S0 and the initial phase are reconstructions
   (`docs/ninebar-parameters.md`, doubt 1). The figures can be matched in trend and
   order of magnitude, not value by value.
2. **Chaotic impacts.** With clearances the motion is chaotic (Sec. 5 of the paper and our
   LLEs): a perturbation of 1e-9 c of the initial state grows to a sizeable part of c within a
   crank cycle, so a peak of one run is one sample of a wide distribution. Every case is
   therefore an ensemble, and a claim is decided only beyond the realisations' scatter; the
   paper's figures are single runs, one sample each. The paper's run conditions (initial state,
   transient, output step) are not stated beyond an "integration step 0.001 s", which can only
   be its output step (spec, doubt 3): a 1 ms output step under-samples contact peaks that last
   1e-5 to 1e-3 s, so the paper's peaks are probably lower than the true ones.
3. **Torques.** The paper's crank torque peaks exceed what its own contact forces allow
   (spec, doubt 2); they are listed but are not validation targets.
4. **Friction coefficient of Sec. 4.2 and 6** is not stated; we use c_f = 0.05 (= mu_k of LuGre).
5. **Sec. 5 run conditions** (clearance, speed, friction for the chaos identification and the
   fixed parameters of the bifurcation diagrams) are not stated; we use those of Sec. 4.3
   (c = 0.1 mm, omega = 2 pi, c_f = 0.01), and the unit of the paper's LLEs is not stated: we
   report 1/s and per crank period.
6. **Friction and the sliding contact.** In our model a larger friction coefficient does not
   calm the journals: the Sec. 4.6 tables give, against c_f, the share of time in contact, the
   contact-force percentiles and the energy balance (driver work against dissipation per
   cycle). Where the journals leave their sliding contact and impact, force peaks and
   stroboscopic spreads grow, the opposite of Sec. 4.6 and Fig. 33. The eigenvalues of the
   model's Jacobian at continuous contact show why: a friction-induced (mode-coupling,
   flutter) instability of the sliding contact whose growth rate rises with c_f (Sec. 4.6's
   flutter table). The model is not tuned to agree with the paper.
"""


def _fmt(x) -> str:
    if x is None:
        return "–"
    if isinstance(x, float):
        return "–" if math.isnan(x) else f"{x:.4g}"
    return str(x)


_VERDICT_STYLE = {
    "reproduced": "**reproduced**",
    "contradicted": "**contradicted**",
    "not resolved": "**not resolved**",
    "undecided": "undecided",
}


def _stats(d: dict, percent: bool = False) -> str:
    """'median (q25-q75)' of a describe() result."""
    if not d or not d.get("n"):
        return "–"
    if percent:
        return f"{100 * d['median']:.0f} % ({100 * d['q25']:.0f}-{100 * d['q75']:.0f})"
    return f"{_fmt(d['median'])} ({_fmt(d['q25'])} to {_fmt(d['q75'])})"


def _section_order(name: str) -> tuple:
    """Sort key: the paper's section, then the name."""
    from workbench.study._spec import load_study

    section = load_study(name).section
    return (tuple(int(x) for x in section.split(".") if x.isdigit()), name)


def write_report(
    out: str | os.PathLike = "out/studies", path: str | os.PathLike | None = None
) -> Path:
    """Collect ``<out>/<study>/summary.json`` of every study into a Markdown report at ``path``
    (written atomically; default :func:`workbench.study.report_path`: ``studies/REPORT.md`` in
    the repository, ``<out>/REPORT.md`` from an installed package). Studies that have not been
    run are listed as such."""
    out = Path(out)
    path = report_path(out) if path is None else path
    cpu = platform.processor() or platform.machine()
    body: list[str] = []
    timing_rows = []
    totals = {v: 0 for v in _VERDICT_STYLE}
    runs = wall = study_wall = 0.0
    for name in sorted(available_studies(), key=_section_order):
        f = out / name / "summary.json"
        if not f.is_file():
            body += [f"## {name}", "", "Not run yet (`workbench study " + name + "`).", ""]
            continue
        s = json.loads(f.read_text())
        body += _study_section(s)
        for c in s["claims"]:
            totals[c["verdict"]] += 1
        study_wall += s.get("wall_time", 0.0)
        for case, v in s["cases"].items():
            runs += v["runs"]
            wall += v["wall_time"]
            timing_rows.append(
                f"| {name}/{case} | {v['runs']} ({v.get('failed_runs', 0)} failed) | "
                f"{_stats(v['seconds_per_cycle'])} | "
                f"{_fmt(v['paper_seconds_per_cycle'])} | {_fmt(v['wall_time'])} |"
            )
    lines = [
        "# The paper's studies, reproduced and compared",
        "",
        "Generated by `workbench study report` from the study summaries in "
        f"`{out}` on {datetime.now(UTC):%Y-%m-%d %H:%M} UTC ({cpu}, "
        f"{os.cpu_count()} CPUs). Regenerate everything with `make studies`. Do not edit by hand.",
        "",
        "Paper: Chen et al., nine-bar mechanism with two revolute clearance joints (the seed "
        "paper). With clearances the motion is chaotic: a peak of one run is one sample of a "
        "distribution. **Every case is therefore run as an ensemble**: N realisations whose "
        "initial states differ by `perturbation` (1e-9) times each state's characteristic size "
        "(the clearance c for positions, c omega for rates), drawn from N(0, 1) with the "
        "realisation number as seed; realisation 0 is unperturbed (`[run] realisation`, "
        "`workbench/run/_ensemble.py`). N and the cycles per realisation are stated per study.",
        "",
        "**Verdicts.** A comparison of two cases (peaks, stroboscopic spreads, computing "
        "times) uses one value per realisation: it is *reproduced* or *contradicted* only "
        "where a two-sided Mann-Whitney U test at 5 % rejects equal distributions, and then "
        "the sign of the difference of the medians decides; otherwise it is *not resolved* "
        "(the difference is within the realisations' scatter). Peaks are compared by "
        "magnitude over the whole record. A sign claim (every LLE positive) uses a two-sided "
        "Wilcoxon signed-rank test at 5 %. A bifurcation claim compares the spreads of every "
        "point (and realisation) of one parameter range with those of the other, by the same "
        "Mann-Whitney rule. Every verdict other than *reproduced* carries its reason.",
        "",
        f"**Totals:** {totals['reproduced']} reproduced, {totals['contradicted']} "
        f"contradicted, {totals['not resolved']} not resolved, {totals['undecided']} "
        f"undecided, of {sum(totals.values())} conclusions.",
        "",
        "Paper values: ours are the median and interquartile range (IQR) over the realisations "
        "of the peak magnitude (the value of largest magnitude) over the first two recorded "
        "crank cycles; 'same sign' counts the realisations whose peak has the paper's sign; "
        "'ratio' is median / |paper|; a paper value outside the range of our realisations "
        "carries the known cause that is the likeliest reason.",
        "",
        *body,
        "## Computing time",
        "",
        f"All studies: {int(runs)} runs; {study_wall / 60:.1f} min of wall time in total "
        f"({wall / 60:.1f} min in the ensemble campaigns on the local process pool, the rest "
        "in the analyses and figures).",
        "",
        "| case | runs | ours [s per crank cycle]: median (IQR) | paper's MATLAB [s per cycle] "
        "| whole ensemble [s] |",
        "|---|---|---|---|---|",
        *timing_rows,
        "",
        _CAUSES,
    ]
    return write_text_atomic(path, "\n".join(lines))


def _study_section(s: dict) -> list[str]:
    lines = [f"## Sec. {s['section']}, {_figures_label(s['paper_figures'])}: {s['title']}", ""]
    if s.get("quick"):
        lines += ["*Quick run (`--quick`): shortened, not evidence.*", ""]
    cycles = "; ".join(f"`{c}` {n} + {t} transient" for c, (n, t) in s.get("cycles", {}).items())
    lines += [
        f"Ensemble: {s['realisations']} realisation(s) per case, perturbation "
        f"{s['perturbation']:g}; crank cycles recorded per realisation: {cycles}."
        + (f" {s['note']}" if s.get("note") else ""),
        "",
        "Cases: " + "; ".join(f"`{c}` ({v['title']})" for c, v in s["cases"].items()),
        "",
    ]
    if s.get("views"):
        lines += [
            "Views (one point of a swept case, compared like a case): "
            + "; ".join(
                f"`{n}` = `{v['case']}` at "
                + ", ".join(f"{k} = {x:g}" for k, x in v["select"].items())
                for n, v in s["views"].items()
            ),
            "",
        ]
    if s["paper_values"]:
        lines += [
            "| case | quantity | paper | ours: median (IQR) | N | same sign | units | ratio | "
            "note |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for r in s["paper_values"]:
            stat = "" if r["statistic"] == "peak" else f" ({r['statistic']})"
            n = r["ours"]["n"]
            sign = f"{r['same_sign']}/{n}" if r["statistic"] == "peak" else "–"
            lines.append(
                f"| {r['case']} | {r['quantity']}{stat} | {_fmt(r['paper'])} | "
                f"{_stats(r['ours'])} | {n} | {sign} | {r['units']} | "
                f"{_fmt(r['ratio_of_medians'])} | {r['note'] or 'within our range'} |"
            )
        lines.append("")
    if s["claims"]:
        lines += ["| paper's conclusion | verdict | evidence | reason |", "|---|---|---|---|"]
        for c in s["claims"]:
            lines.append(
                f"| {_cell(c['text'])} | {_VERDICT_STYLE[c['verdict']]} | "
                f"{_cell(c['evidence'])} | {_cell(c.get('reason') or '–')} |"
            )
        lines.append("")
    m = s.get("measures", {})
    lines += _friction_law_table(m)
    if m.get("wolf_lle"):
        lines += _chaos_table(m)
    for case, sweep in m.get("sweep_contact", {}).items():
        lines += _sweep_table(case, sweep)
    if s.get("flutter"):
        lines += _flutter_section(s["flutter"])
    if s.get("route"):
        lines += route_section(s["route"])
    if s["figures"]:
        lines += ["Figures: " + ", ".join(f"`{p}`" for p in s["figures"]), ""]
    return lines


def _cell(text: str) -> str:
    """Text for a Markdown table cell: its bars escaped (|F_t|, |peak|), which would
    otherwise split the row."""
    return str(text).replace("|", "\\|")


def _friction_law_table(m: dict) -> list[str]:
    """The friction law's range per case (studies with a LuGre case): the largest |F_t| / F_n
    at the records, the time above mu_s and beyond the LuGre envelope per crank cycle, and the
    99th-percentile contact force."""
    from workbench.study._stats import describe

    law = m.get("friction_law", {})
    if not any(math.isfinite(x) for v in law.values() for x in v.get("above", []) if x is not None):
        return []
    lines = [
        "The friction law's range, median (IQR) over the realisations: the friction coefficient "
        "|F_t| / F_n at the records, its median in contact and its largest, and per crank cycle "
        "the time (summed over the "
        "joints, integrated with the motion) with it above mu_s and beyond the LuGre law's "
        "envelope 2 mu_s + sigma2 |v_t| (`workbench/models/_friction_report.py`); a passive "
        "law stays within the envelope, Coulomb within c_f.",
        "",
        "| case | \\|F_t\\|/F_n in contact: median | largest | above mu_s [ms per cycle] | "
        "beyond the envelope [ms per cycle] | 99th-percentile contact force [N] |",
        "|---|---|---|---|---|---|",
    ]
    for case, v in law.items():
        ms = {k: [1e3 * x for x in v.get(k, []) if x is not None] for k in ("above", "beyond")}
        contact = m.get("contact", {}).get(case, {})
        force = ", ".join(f"{j} {_fmt(describe(c['p99'])['median'])}" for j, c in contact.items())
        lines.append(
            f"| {case} | {_stats(describe(v.get('mu_median', [])))} | "
            f"{_stats(describe(v['mu_max']))} | {_stats(describe(ms['above']))} | "
            f"{_stats(describe(ms['beyond']))} | {force or '–'} |"
        )
    return lines + [""]


def _chaos_table(m: dict) -> list[str]:
    from workbench.study._stats import describe

    lines = [
        "Beyond the paper: the 0-1 test for chaos (Gottwald & Melbourne 2004; K near 0 "
        "regular, near 1 chaotic) of the stroboscopic samples beside the Wolf LLE, median "
        "(IQR) over the realisations.",
        "",
        "| coordinate | Wolf LLE [1/s] | per crank period | 0-1 test K |",
        "|---|---|---|---|",
    ]
    for k, v in m["wolf_lle"].items():
        lines.append(
            f"| {k} | {_stats(describe(v))} | "
            f"{_stats(describe(m.get('wolf_lle_per_period', {}).get(k, [])))} | "
            f"{_stats(describe(m.get('zero_one_K', {}).get(k, [])))} |"
        )
    return lines + [""] + _exponent_table(m.get("exponents"))


def _agreement(e: dict) -> str:
    """What the two exponents from the equations (same trajectory) say, from their numbers."""
    if "variational, same trajectory" not in e["method"]:
        return ""
    if "spectrum_stderr" not in e:  # written before the estimates grew to an error target
        return (
            "This summary predates the exponents' convergence in time: its estimates from the "
            f"equations come from {e.get('cycles')} crank cycles with knob variants on one "
            "trajectory only, which is not enough to call any of them the exponent; "
            "`workbench study chaos` recomputes them."
        )
    i = e["method"].index("two trajectories")
    j = e["method"].index("variational, same trajectory")
    a, b, err = e["lle"][i], e["lle"][j], e["stderr"][i]
    if abs(a - b) <= 2 * err and e["trusted"][i]:
        return (
            f"The two-trajectory estimate ({_fmt(a)} +/- {_fmt(err)} 1/s) and the variational "
            f"exponent on the same trajectory ({_fmt(b)} 1/s) agree within two standard errors, "
            "and the estimate converged: this is the exponent."
        )
    return (
        f"The two-trajectory estimate ({_fmt(a)} +/- {_fmt(err)} 1/s) and the variational "
        f"exponent on the same trajectory ({_fmt(b)} 1/s) "
        + ("agree within two standard errors" if abs(a - b) <= 2 * err else "differ")
        + (", but the estimate did not converge" if not e["trusted"][i] else "")
        + ": the exponent is known only to that precision (see the evidence column)."
    )


def _exponent_table(e: dict | None) -> list[str]:
    """The largest Lyapunov exponent of realisation 0 by every method, and what the paper's
    unitless LLEs could be."""
    if not e:
        return []
    T = e.get("forcing_period") or 1.0
    lines = [
        f"The largest Lyapunov exponent by every method ({e.get('cycles')} crank cycles after "
        f"{e.get('transient_cycles')} for the equations, shared among independent starts, "
        "realisations 0-3, for the two-trajectory estimate; realisation 0 for the others; "
        f"Wolf on {e.get('coordinate')}; the equations' windows grow until the standard error "
        "is 3 % of the estimate). *trusted*: converged (the equations' estimates: error target "
        "met, halved and doubled knobs within 5 % and two standard errors, runs at rtol/100 "
        "and the variational exponent within two standard errors) or not flagged (Wolf's own "
        "sampling, length and noise checks).",
        "",
        "| method | LLE [1/s] | per crank cycle | standard error [1/s] | trusted | evidence |",
        "|---|---|---|---|---|---|",
    ]
    for i, method in enumerate(e["method"]):
        lines.append(
            f"| {method} | {_fmt(e['lle'][i])} | {_fmt(e['lle_per_cycle'][i])} | "
            f"{_fmt(e['stderr'][i])} | {'yes' if e['trusted'][i] else 'no'} | {e['note'][i]} |"
        )
    ref = e["lle"][e["method"].index("two trajectories")]
    values = e.get("spectrum", [])
    errors, trusted = e.get("spectrum_stderr"), e.get("spectrum_trusted")
    if errors is None or trusted is None or len(errors) != len(values):
        # a summary written before the exponents carried errors: its values, said so
        spectrum = ", ".join(_fmt(v) for v in values) + (
            " (no standard errors: this summary predates them; `workbench study chaos` "
            "computes them)"
        )
    else:
        spectrum = ", ".join(
            f"{_fmt(v)} +/- {_fmt(err)}{'' if ok else ' (not trusted)'}"
            for v, err, ok in zip(values, errors, trusted, strict=True)
        )
    spp = 100
    per_sample = ref * T / spp
    lines += [
        "",
        f"Largest exponents (variational equations over {_fmt(e.get('spectrum_cycles'))} "
        f"cycles, 1/s, +/- standard error): {spectrum}. Their sum against the rate of the log "
        "volume the tangent vectors span, integrated with the tangent system: relative "
        f"difference {_fmt(e.get('sum_check'))}.",
        "",
        _agreement(e),
        "",
        "Why Wolf's estimates differ: Wolf's method needs the separation of neighbouring states to "
        "grow smoothly between samples; at 100 samples per cycle a contact (a few ms) lies "
        "between two samples, the series is a map to Wolf's test, and the estimate is flagged; "
        "finer sampling approaches the equations' value as far as the series resolves the "
        "impacts. The stroboscopic map has one sample per cycle: its exponent per iteration "
        "is the exponent per cycle, but a few hundred samples leave it noisy.",
        "",
        "What the paper's LLEs (0.14-0.61, unit not stated) could be, without claiming a match: "
        f"per second they would be {ref / 0.61:.0f}-{ref / 0.14:.0f}x below the exponent "
        f"({_fmt(ref)} 1/s); per crank cycle ({_fmt(ref * T)}) likewise; per sample of a "
        f"100-per-cycle series (the paper's 0.01 s output at omega = 2 pi) it is "
        f"{per_sample:.3g}, or {per_sample / math.log(2):.3g} bits per sample (Wolf et al. "
        "1985 report bits), which is of their size; the paper's Wolf settings are not stated, "
        "so this is a possibility, not a reproduction.",
        "",
    ]
    return lines


def _sweep_table(case: str, d: dict) -> list[str]:
    """Contact fraction, force percentiles and energy balance against the swept parameter."""
    joints = d["joints"]
    pct = d["percentiles"]
    head = [d["parameter"]]
    head += [f"in contact at {j}" for j in joints]
    head += [f"force {'/'.join(f'{q:g}' for q in pct)} % at {j} [N]" for j in joints]
    energy = "driver_work_per_cycle" in d and "dissipated_energy_per_cycle" in d
    if energy:
        head += ["driver work [J per cycle]", "dissipated [J per cycle]"]
    lines = [
        f"Contact against {d['parameter']} in `{case}` (c = {d['clearance'] * 1e3:g} mm): "
        "medians over the realisations (IQR in parentheses); contact: share of the recorded "
        "time with a contact force; force percentiles over the recorded time (0 while out of "
        "contact).",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    frac = d["contact_fraction"]
    force = d["contact_force_percentile"]
    for i, v in enumerate(d["values"]):
        row = [f"{v:g}"]
        for k in range(len(joints)):
            row.append(
                _stats(
                    {
                        "n": 1,
                        "median": frac["median"][i][k],
                        "q25": frac["q25"][i][k],
                        "q75": frac["q75"][i][k],
                    },
                    percent=True,
                )
            )
        for k in range(len(joints)):
            # dims of the percentiles: (percentile, parameter, joint)
            row.append(" / ".join(f"{force['median'][p][i][k]:.4g}" for p in range(len(pct))))
        if energy:
            for name in ("driver_work_per_cycle", "dissipated_energy_per_cycle"):
                e = d[name]
                row.append(
                    _stats(
                        {"n": 1, "median": e["median"][i], "q25": e["q25"][i], "q75": e["q75"][i]}
                    )
                )
        lines.append("| " + " | ".join(row) + " |")
    return lines + [""]


def _flutter_section(spec: dict) -> list[str]:
    """The flutter of the sliding contact against the friction coefficient (see
    ``workbench.study._flutter.flutter``)."""
    if spec.get("status") != "computed":
        return []
    param = spec["parameter"]
    lines = [
        "**Flutter of the sliding contact.** Eigenvalues of the rhs Jacobian "
        "(`workbench.analysis.jacobian_spectrum`) at the records where both journals are in "
        "contact, one crank cycle at 200 records per cycle after the transient: the median "
        "and 90th percentile of the largest real part, the frequency of the largest, the share "
        "of records in continuous contact. A positive real part is a growing oscillation of "
        "the sliding contact (friction-induced mode coupling; Hoffmann et al. 2002); the onset "
        "is where the median first exceeds the crank frequency (the mode then grows e-fold "
        "within a crank cycle).",
        "",
    ]
    for case, rows in spec["cases"].items():
        lines += [
            f"`{case}` (onset {param} = {_fmt(rows['onset'])}; crank frequency "
            f"{rows['threshold']:.3g} Hz):",
            "",
            f"| {param} | both in contact | largest real part, median [1/s] | 90 % [1/s] | "
            "frequency [Hz] |",
            "|---|---|---|---|---|",
        ]
        for i, v in enumerate(rows["values"]):
            lines.append(
                f"| {v:g} | {rows['fraction'][i]:.0%} | {_fmt(rows['median'][i])} | "
                f"{_fmt(rows['p90'][i])} | {_fmt(rows['frequency'][i])} |"
            )
        lines.append("")
    return lines


def _figures_label(figures: str) -> str:
    """'Fig. 31' for one figure, 'Figs. 4-9' for several."""
    return f"Figs. {figures}" if any(ch in str(figures) for ch in "-,") else f"Fig. {figures}"
