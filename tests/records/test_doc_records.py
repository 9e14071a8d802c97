"""The numbers docs/analysis.md, docs/continuation.md and docs/robustness.md quote from benchmark
records, from tests and from the code (the project's rule: the docs quote only what the code
produces now, and a test checks each number; docstrings describe and quote none). Each test
reads the page and the records it names (benchmarks/records/: one JSON file per run,
benchmarks/_results.py), the measurement made by hand (benchmarks/NOTES.md) or the test that
asserts the figure, and asserts that they agree: a current figure is the newest record of its
benchmark (and window), a "before" figure the record the page names, a tested figure the value
its test asserts. A record's numbers are formatted as the benchmark prints them (and the page
quotes them)."""

import json
import math
import re
from pathlib import Path

import pytest
from _records import NOTES, ROOT, records

#: `benchmarks/lle.py` records made before the copies were renormalised on shrinkage as well
#: (25aee46), which docs/analysis.md quotes as "before": the separation scans and the default call
BEFORE_SHRINK_SCANS = ("d99dfdb", "968e2fe", "968e2fe-dirty")
BEFORE_SHRINK_CHAOS = "be0fa29"


def _page(name: str) -> str:
    """A page of docs/ with its whitespace collapsed."""
    return " ".join((ROOT / "docs" / name).read_text().split())


def _test_file(name: str):
    """The test file called ``name`` (a basename: test files are unique by name under tests/)."""
    (path,) = (ROOT / "tests").rglob(name)
    return path


def _test_source(path: str, name: str) -> str:
    """The source of one test function of the test file ``path`` (up to the next top-level def)."""
    source = _test_file(path).read_text()
    return re.split(r"\n(?:@|def )", source.split(f"def {name}(")[1])[0]


def _contracting_orbit_test() -> tuple[str, str]:
    """The two-trajectory and variational exponents of the nine-bar's stable orbit (omega =
    0.5 pi, c = 20 um, one cycle) that tests/analysis/test_lyapunov.py asserts, as it writes
    them."""
    test = _test_source(
        "test_lyapunov.py", "test_contracting_nine_bar_orbit_reads_a_negative_exponent"
    )
    assert "with_parameters(omega=0.5 * math.pi, clearance=2e-5)" in test
    return re.search(
        r"assert abs\(float\(r\.lle\) - (-[\d.]+)\) < [\d.]+ and "
        r"abs\(float\(r\.lle_variational\) - (-[\d.]+)\) < [\d.]+",
        test,
    ).groups()


def _floquet_bound_test() -> str:
    """The upper bound of that orbit's Floquet exponent that tests/continuation/test_continuation.py
    asserts."""
    test = _test_source(
        "test_continuation.py",
        "test_a_contracting_nine_bar_orbit_gets_a_floquet_bound_not_the_noise_rate",
    )
    assert "with_parameters(omega=0.5 * math.pi, clearance=2e-5)" in test
    return re.search(r"assert abs\(float\(ind\.lle\) - (-[\d.]+)\) <", test)[1]


def _and(items) -> str:
    items = list(items)
    return ", ".join(items[:-1]) + " and " + items[-1]


def _n(token: str) -> str:
    """A count as the pages write it: 840832 -> "840 832"."""
    return f"{int(token):,}".replace(",", " ") if token.isdigit() else token


def _e(token: str) -> str:
    """A relative difference as the pages write it: 0.00029 -> "2.9e-4"."""
    mantissa, exponent = f"{float(token):.1e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _g(token: str) -> str:
    """A record's ``%.3g`` figure below 1e-4 as the pages write it: "3.23e-06" -> "3.23e-6"."""
    mantissa, exponent = token.split("e")
    return f"{mantissa}e{int(exponent)}"


# -- benchmarks/tangent_speed.py ------------------------------------------------------------------
#: the columns of a run's row as the script prints them (figure, format): CPU s/cyc, x plain,
#: steps/cyc, rej/cyc, evals/cyc, events/cyc, QR/cyc, sum, volume rate, rel
COLUMNS = (
    ("cpu_s_per_cycle", ".4g"),
    ("times_plain", ".4g"),
    ("steps_per_cycle", ".6g"),
    ("rejected_per_cycle", ".6g"),
    ("evaluations_per_cycle", ".6g"),
    ("events_per_cycle", ".6g"),
    ("reorthonormalisations_per_cycle", ".6g"),
    ("exponent_sum", ".6g"),
    ("volume_rate", ".6g"),
    ("sum_check", ".2g"),
)
CPU, RATIO, STEPS, EVENTS, QR, REL = 0, 1, 2, 5, 6, 9


def _tangent_records() -> list[dict]:
    """Every ``tangent_speed.py`` record, oldest first: its file, commit, note, window (as the
    script prints it) and each run's row of columns (as printed)."""
    found = []
    for r in records("tangent_speed.py"):
        f = r["figures"]
        rows = {
            run: [format(values[k], spec) for k, spec in COLUMNS if k in values]
            for run, values in f["runs"].items()
        }
        window = {"cycles": f"{f['cycles']:g}", "t0": f"{f['t0']:.3f}", "rtol": f"{f['rtol']:g}"}
        found.append(
            {"file": r["file"], "commit": r["commit"], "note": r.get("note", ""), "rows": rows}
            | window
            | {"defect": f"{f['defect']:g}"}
        )
    return found


def test_the_analysis_page_names_where_the_tangent_records_are():
    """docs/analysis.md names the folder of the tangent_speed records, which holds them all."""
    found = _tangent_records()
    assert len(found) >= 11 and {Path(r["file"]).parent.name for r in found} == {"tangent_speed"}
    assert "its records are in `benchmarks/records/tangent_speed/`" in _page("analysis.md")


def _newest(records: list[dict], cycles: str, rtol: str, defect: str, run: str) -> dict:
    """The newest record of a window (cycles, rtol, defect) that has the row ``run``."""
    return [
        r
        for r in records
        if (r["cycles"], r["rtol"], r["defect"]) == (cycles, rtol, defect) and run in r["rows"]
    ][-1]


def _full(records: list[dict], cycles: str) -> dict:
    """The newest record of a window (cycles, rtol 1e-6, the default defect 10) with the
    plain run and 1, 4 and 8 exponents."""
    return [
        r
        for r in records
        if {"plain", *RUNS} <= r["rows"].keys()
        and (r["cycles"], r["rtol"], r["defect"]) == (cycles, "1e-06", "10")
    ][-1]


RUNS = ("m = 1", "m = 4", "m = 8")


def test_the_tangent_cost_is_the_newest_tangent_speed_record():
    """docs/analysis.md, "What the tangent system costs": the newest record with 1, 4 and 8
    exponents at the scene's rtol and the default defect over 2 cycles, and the record before
    issue 39's rework of the tangent system that it compares with."""
    page = _page("analysis.md")
    records = _tangent_records()
    full = _full(records, "2")
    plain, rows = full["rows"]["plain"], [full["rows"][run] for run in RUNS]
    assert float(full["t0"]) == 20.0  # after the scene's 20 transient cycles of 1 s
    assert f"at rtol 1e-6, {full['cycles']} cycles after the 20 transient cycles" in page
    assert f"with 1, 4 and 8 exponents, at {full['commit']} in `{full['file']}`;" in page
    assert f"the model alone takes {plain[CPU]} s and {_n(plain[STEPS])} steps per cycle" in page
    assert (
        f"the tangent run with 1, 4 and 8 exponents {_and(r[CPU] for r in rows)} s per cycle "
        f"({_and(_n(r[RATIO]) for r in rows)} times the model) and "
        f"{_and(_n(r[STEPS]) for r in rows)} steps, with {_and(_n(r[QR]) for r in rows)} "
        "re-orthonormalisations per cycle"
    ) in page
    (before,) = [r for r in records if "before issue 39 item 3" in r["note"]]
    assert (before["cycles"], before["rtol"], before["defect"]) == ("2", "1e-06", "10")
    old = [before["rows"][run] for run in RUNS]
    assert (
        f"the record at {before['commit']} in `{before['file']}`), the same window cost "
        f"{_and(_n(r[RATIO]) for r in old)} times the model, with sum checks "
        f"{_and(_e(r[REL]) for r in old)}"
    ) in page


def test_the_sum_checks_are_the_newest_tangent_speed_records():
    """docs/analysis.md, "The sum check": each window's sum checks from the newest record of
    that window, and the commits it names."""
    page = _page("analysis.md")
    records = _tangent_records()
    two, half = _full(records, "2"), _full(records, "0.5")
    short = _newest(records, "0.05", "1e-06", "10", "m = 8")
    tight = _newest(records, "2", "1e-08", "10", "m = 4")
    assert len({r["commit"].removesuffix("-dirty") for r in (two, half, short, tight)}) == 1
    assert f"the newest records of each window, at {two['commit'].removesuffix('-dirty')};" in page

    def rel(r, run="m = 4"):
        return _e(r["rows"][run][REL])

    assert (
        f"1, 4 and 8 exponents close to {_and(rel(two, run) for run in RUNS)} over 2 cycles and "
        f"to {_and(rel(half, run) for run in RUNS)} over 0.5 cycles"
    ) in page
    # the 0.05-cycle window is tests/analysis/test_lyapunov.py's sum-check test's
    assert (
        f"all 8 close to {rel(short, 'm = 8')} over 0.05 cycles (`tests/analysis/test_lyapunov.py`)"
        in page
    )
    row = half["rows"]["m = 4"]
    assert f"({row[7]} 1/s against a volume rate of {row[8]} 1/s)" in page
    assert f"at rtol 1e-8 the 4 exponents close to {rel(tight)} over the 2 cycles" in page


# -- benchmarks/lle.py ---------------------------------------------------------------------------
def chaos_records() -> list[dict]:
    """The ``benchmarks/lle.py --chaos`` records, oldest first."""
    return [
        r for r in records("lle.py") if r["command"].startswith("python benchmarks/lle.py --chaos")
    ]


def _chaos_numbers(record: dict) -> tuple[str, ...]:
    """An ``lle.py --chaos`` record's call at rtol 1e-6: the estimate and its error, the
    variational exponent, their difference and its error, as the benchmark prints them."""
    f = record["figures"]["1e-06"]
    return (
        f"{f['lle']:.2f}",
        f"{f['stderr']:.2f}",
        f"{f['lle_variational']:.2f}",
        f"{f['difference']:+.3f}",
        f"{f['stderr_difference']:.3f}",
    )


def scan_means(record: dict, d0: float) -> dict[str, float]:
    """An ``lle.py --scan`` record's mean difference at separation ``d0``, per tolerance (the
    key its scan has: "1e-06", or "1e-06, max_step 0.0001 s" with the step capped)."""
    return {
        key: scan["mean_difference"][[f"{d:.0e}" for d in scan["separations"]].index(f"{d0:.0e}")]
        for key, scan in record["figures"].items()
    }


def test_the_chaos_case_before_and_now_are_the_lle_records():
    """docs/analysis.md, "Contracting orbits": the default call on the chaos case before the
    copies were renormalised on shrinkage (the record it names) and now (the newest)."""
    page = _page("analysis.md")
    chaos = chaos_records()
    (before,) = [r for r in chaos if r["commit"] == BEFORE_SHRINK_CHAOS]
    b, n = _chaos_numbers(before), _chaos_numbers(chaos[-1])
    assert (
        f"before (the `benchmarks/lle.py --chaos` record at {BEFORE_SHRINK_CHAOS} in "
        f"`benchmarks/RESULTS.md`), {b[0]} +/- {b[1]} 1/s at rtol 1e-6 and the variational "
        f"exponent on the same trajectories {b[2]} (difference {b[3]} +/- {b[4]}), now (the "
        f"newest record, at {chaos[-1]['commit']}) {n[0]} +/- {n[1]} and {n[2]} ({n[3]} +/- "
        f"{n[4]})"
    ) in page


def test_the_noise_floor_before_and_now_are_the_scans():
    """docs/analysis.md, "One answer from both methods": the noise floor at d0 = 1e-10 and
    1e-9 over every run of the separation scan (benchmarks/results/lle_separation_scan.json,
    the newest scans), and before the shrink renormalisation (the ``--scan`` records it names)."""
    page = _page("analysis.md")
    scan = json.loads((ROOT / "benchmarks/results/lle_separation_scan.json").read_text())["scan"]
    at = {
        d0: [e["mean_difference"][e["separations"].index(d0)] for e in scan.values()]
        for d0 in (1e-10, 1e-9)
    }
    lo, hi = min(at[1e-10]), max(at[1e-10])
    assert f"a noise floor lifts the estimate by {lo:.0f}-{hi:.0f} 1/s at every tolerance" in page
    lo, hi = min(at[1e-9]), max(at[1e-9])
    assert f"at 1e-9 what is left of it is +{lo:.1f}-{hi:.1f} 1/s" in page

    before = [r for r in records("lle.py") if r["commit"] in BEFORE_SHRINK_SCANS]
    before = [r for r in before if "--scan" in r["command"]]
    floor = {d0: [m for r in before for m in scan_means(r, d0).values()] for d0 in (1e-10, 1e-9)}
    assert len(floor[1e-10]) == 4  # rtol 1e-6 with the step free and capped, 1e-8, 1e-10
    assert f"the `--scan` records at {_and(BEFORE_SHRINK_SCANS)} in `benchmarks/RESULTS.md`" in page
    (free,) = [scan_means(r, 1e-8)["1e-06"] for r in before if "1e-06" in r["figures"]]
    assert (
        f"(+{min(floor[1e-10]):.1f}-{max(floor[1e-10]):.1f} 1/s at 1e-10 and "
        f"+{min(floor[1e-9]):.1f}-{max(floor[1e-9]):.1f} at 1e-9 in every run, "
        f"+{free:.1f} at 1e-8 at rtol 1e-6 with the step free)"
    ) in page


def test_the_decorrelation_time_and_the_shrinkages_are_the_newest_chaos_record():
    """docs/analysis.md: the time after which the starts' windows are independent, ln(1/1e-9) /
    λ at the newest ``--chaos`` record's exponent, and the shrinkages among that record's
    renormalisations at rtol 1e-6."""
    page = _page("analysis.md")
    newest = chaos_records()[-1]
    lle = _chaos_numbers(newest)[0]
    assert (
        f"after ln(1/1e-9) / λ: {math.log(1e9) / float(lle):.1f} s on the chaos case at its "
        f"λ = {lle} 1/s, the newest `benchmarks/lle.py --chaos` record, at {newest['commit']}, "
        "rtol 1e-6)"
    ) in page
    call = newest["figures"]["1e-06"]
    assert (call["starts"], call["cycles_per_start"], call["converged"]) == (4, 20, True)
    total, shrunk = call["renormalisations"][0], call["shrink_renormalisations"][0]
    assert (
        f"at rtol 1e-6, {shrunk} of the estimate's {total} renormalisations over 4 x 20 cycles "
        "were shrinkages (`benchmarks/lle.py --chaos 1e-6`)"
    ) in page


# -- figures of docs/analysis.md and docs/continuation.md that tests assert ----------------------
def test_the_contracting_orbit_figures_are_the_tests():
    """The nine-bar's stable orbit at omega = 0.5 pi, c = 20 um: the two-trajectory and
    variational exponents tests/analysis/test_lyapunov.py asserts and the Floquet bound
    tests/continuation/test_continuation.py asserts, as docs/analysis.md and docs/continuation.md
    quote them;
    the "before" (copies renormalised on growth alone) from the oldest ``benchmarks/
    continuation.py --parts chaos_maps`` record, which docs/continuation.md names."""
    copies, variational = _contracting_orbit_test()
    bound = _floquet_bound_test()
    assert (
        f"| nine-bar, omega = 0.5 pi, c = 20 um (A+B, Coulomb c_f = 0.01), 1 x 1 cycle | {copies} "
        f"| {variational} (variational, same trajectory); a stable period-1 orbit, Floquet "
        f"exponent below the bound {bound} (`tests/continuation/test_continuation.py`) |"
    ) in _page("analysis.md")

    page = _page("continuation.md")
    assert (
        f"and there they now read {copies} 1/s over one cycle, "
        f"{(float(copies) / float(variational) - 1) * -100:.0f} % above the variational "
        f"exponent on the same trajectory ({variational}; `tests/analysis/test_lyapunov.py`"
    ) in page
    assert f"such an orbit: the bound is {bound} 1/s" in page
    # the "before": the oldest chaos_maps record (later ones give the orbit's Floquet bound)
    oldest = next(r for r in records("continuation.py") if "--parts chaos_maps" in r["command"])
    corner = oldest["figures"]["chaos_map_corners"][
        "omega_clearance at omega=1.571, clearance=2e-05"
    ]
    mantissa, exponent = f"{corner['lle']:.3g}".split("e")
    assert (
        f"at omega = 0.5 pi, c = 20 um {mantissa}e{int(exponent)} +- {corner['lle_stderr']:.2g} "
        f"1/s, the `benchmarks/continuation.py --parts chaos_maps` record at {oldest['commit']})"
    ) in page


def test_the_short_chaos_window_is_the_test_s():
    """docs/analysis.md, "When an exponent has converged": the chaos case over 3 cycles as
    tests/analysis/test_lyapunov.py asserts it."""
    test = _test_source("test_lyapunov.py", "test_chaos_case_two_trajectory_and_variational_agree")
    assert '"cycles": 3' in test
    short, err = re.search(
        r"assert agrees\(float\(r\.lle\), float\(r\.stderr\), ([\d.]+), ([\d.]+)\)", test
    ).groups()
    assert f"(over 3 cycles the chaos case read {short} +/- {err} 1/s" in _page("analysis.md")


def test_the_fnn_plateau_figure_is_the_heldout_test_s():
    """docs/analysis.md, the Wolf estimate's embedding: the bound
    tests/analysis/test_wolf_heldout.py holds a Duffing section's estimate to in the plateau's
    first dimension."""
    test = _test_source("test_wolf_heldout.py", "test_heldout_duffing_section")
    assert "assert float(r.lle) == pytest.approx(per_period, rel=FLOW_GROSS)" in test
    source = _test_file("test_wolf_heldout.py").read_text()
    rel = float(
        re.search(r"^FLOW_BOUND, FLOW_GROSS, FLOW_MISSES = [\d.]+, ([\d.]+),", source, re.M)[1]
    )
    assert (
        f"in the plateau's first dimension a Duffing section's estimate is within "
        f"{rel * 100:.0f} % of the exponent: `tests/analysis/test_wolf_heldout.py`"
    ) in _page("analysis.md")


# -- docs/robustness.md ---------------------------------------------------------------------------
def test_the_interrupt_figures_are_the_code_s_and_its_test_s():
    """docs/robustness.md, "Interrupts": the pause is the solver's constant, and the latency it
    quotes for ``workbench run -q`` is the bound tests/run/test_faults_run.py asserts."""
    from workbench.solver import PAUSE_SECONDS

    page = _page("robustness.md")
    assert f"`workbench.solver.PAUSE_SECONDS` = {PAUSE_SECONDS:g} s of wall time" in page
    source = _test_file("test_faults_run.py").read_text()
    test = source.split("def test_cli_run_quiet_stops_on_a_signal_in_one_line")[1]
    bound = float(re.search(r"assert latency < ([\d.]+)", test).group(1))
    assert f"`workbench run: interrupted` within the {bound:g} s from the signal that" in page


def test_the_models_page_quotes_the_lugre_damping_record():
    """docs/models.md: the paper's constant bristle damping takes |F_t|/F_n to the peak that the
    hand-written ``lugre_damping.py`` section of benchmarks/NOTES.md records."""
    record = " ".join(NOTES.read_text().split())
    peak = re.search(r"constant damping \(316\.2 s/m\) reaches ([\d.]+),", record).group(1)
    assert f"|F_t|/F_n to tens ({peak} on the paper's Sec. 4.2 case" in _page("models.md")
    assert 10 <= float(peak) < 100  # "tens"


def test_the_grazing_curves_of_the_audit_are_the_newest_stop_curve_record():
    """docs/continuation.md, the grazing audit's curves in the force: the newest
    ``grazing_audit.py --systems stop-curve`` record, its command, counts and the curves that
    turn at the least grazing force (within the audit's 1e-6 of it)."""
    page = _page("continuation.md")
    runs = [r for r in records("grazing_audit.py") if "stop-curve" in r["command"]]
    newest = runs[-1]
    out = newest["figures"]
    rows = out["rows"]
    assert newest["command"].endswith("--seed 13 --cases 10 --systems stop-curve")
    assert "`python benchmarks/grazing_audit.py --seed 13 --cases 10 --systems stop-curve`" in page
    right = sum(r["curve_relative_error"] <= 1e-6 for r in rows)
    covered = sum(r["curve_covered"] for r in rows)
    assert (out["curves"], out["curves_right"], right, covered) == (10, 10, 10, 10)
    assert "10 grazing curves, 10 within 1e-06 of the closed form at every point, 10 covering" in (
        page
    )
    turned = [r for r in rows if r["curve_force_range"][0] > 0.8 * r["parameters"]["force"]]
    assert len(turned) == 2 and "two of them turn in the force" in page
    for r in turned:
        assert "second_parameter_turn" in r["curve_special"]
        assert abs(r["curve_force_range"][0] / r["least_force"] - 1) < 1e-6


def test_the_impact_oscillator_s_grazing_curves_are_the_newest_impact_curve_record():
    """docs/continuation.md: the audit's rigid impact oscillators, whose grazing curves in the
    force do not get away from their start (the newest ``--systems impact-curve`` record)."""
    page = _page("continuation.md")
    runs = [r for r in records("grazing_audit.py") if "impact-curve" in r["command"]]
    newest = runs[-1]
    rows = newest["figures"]["rows"]
    assert newest["command"].endswith("--seed 3 --cases 5 --systems impact-curve")
    assert "benchmarks/grazing_audit.py --seed 3 --cases 5 --systems impact-curve`" in page
    assert all(r["relative_error"] <= 1e-6 and r["curve_relative_error"] <= 1e-6 for r in rows)
    stuck = [r for r in rows if r["curve_points"] == 1]
    (moved,) = [r for r in rows if r["curve_points"] > 1]
    assert len(stuck) == 4 and not any(r["curve_covered"] for r in rows)
    low = moved["curve_force_range"][0] / moved["parameters"]["force"]
    assert f"4 of the 5 curves stop at their first point and the fifth reaches {low:.2f}" in page
    assert all(r["curve_ended"].count("the corrector failed at the least step") == 2 for r in rows)


def test_the_map_check_on_the_same_orbit_is_the_newest_same_orbit_record():
    """docs/continuation.md, the (omega, c) map's subset check: the newest
    ``chaos_map_agreement.py --same-orbit`` record's counts (periodic points, agreement on the
    fast value's own orbit and on the orbit integrated again, held velocities that differ, the
    chaotic points, the points whose run now ends on another member)."""
    page = " ".join(_page("continuation.md").split())
    newest = [r for r in records("chaos_map_agreement.py") if "--same-orbit" in r["command"]][-1]
    f = newest["figures"]
    rows = f["rows"]
    n = f["periodic"]
    assert (n, f["agree_same_orbit"], f["agree_again"], f["held_differ"]) == (30, 29, 8, 30)
    assert f"computed the {n} periodic points of the {f['shared']} the two maps share" in page
    assert f"other onset velocities at all {f['held_differ']} (by more than 1 %)" in page
    assert f"its exponent agrees with the fast one at {f['agree_again']}." in page
    assert f"agrees at {f['agree_same_orbit']} ({round(100 * f['agree_same_orbit'] / n)} %)" in page
    (odd,) = [r for r in rows if "lle_fast" in r and not r["agree_same_orbit"]]
    assert odd["stderr_fast"] is None and odd["stderr_full_same_orbit"] is None  # bounds (NaN)
    assert f"{odd['lle_fast']:.3g} and {odd['lle_full_same_orbit']:.3g} 1/s" in page
    chaotic = [r for r in rows if "lle_fast" not in r]
    agreeing = sum(r["agree"] for r in chaotic)
    assert f"the {agreeing} of {len(chaotic)} chaotic" in page
    both = agreeing + f["agree_same_orbit"]
    assert f"{both} of the {f['shared']} points ({round(100 * both / f['shared'])} %) agree" in page
    assert f["same_verdict"] == f["shared"] and f"all {f['shared']} have the same verdict" in page
    moved = [
        r for r in rows if "lle_fast" in r and abs(r["lle_fast"] - r["lle"]) > 0.1 * abs(r["lle"])
    ]
    assert f"At {len(moved)} of the {n} periodic points the run itself" in page
    first = min(moved, key=lambda r: r["omega"])
    assert (
        f"its fast exponent reads {first['lle_fast']:.3g} 1/s against the map's {first['lle']:.3g}"
        in page
    )


def test_the_audit_s_other_labels_are_the_newest_reference_records():
    """docs/continuation.md, "The other labels against independent references": the newest
    ``--systems stop,stop-force-gap`` record (every fold and period doubling of a stop
    oscillator against the piecewise-linear reference) and the newest ``--systems
    impact-flip`` record (every flip of the impact oscillator's reference labelled), their
    commands and counts."""
    page = " ".join(_page("continuation.md").split())
    runs = [r for r in records("grazing_audit.py") if r["command"].endswith("stop,stop-force-gap")]
    newest = runs[-1]
    assert newest["command"].endswith("--seed 29 --cases 6 --systems stop,stop-force-gap")
    assert (
        "`python benchmarks/grazing_audit.py --seed 29 --cases 6 --systems stop,stop-force-gap`"
        in page
    )
    checks = [c for r in newest["figures"]["rows"] for c in r.get("label_checks", [])]
    right = [c for c in checks if c[3] is not None and c[3] <= 1e-6]
    worst = max(c[3] for c in right)
    text = f"{len(checks)} folds and period doublings, {len(right)} within 1e-6 of the reference"
    assert text in page and f"(the largest error {worst:.1e})".replace("e-0", "e-") in page
    assert newest["figures"]["stop_labels_misplaced"] == 0
    flips = [r for r in records("grazing_audit.py") if r["command"].endswith("impact-flip")][-1]
    assert flips["command"].endswith("--seed 2 --cases 12 --systems impact-flip")
    assert "`python benchmarks/grazing_audit.py --seed 2 --cases 12 --systems impact-flip`" in page
    rows = flips["figures"]["rows"]
    found = [r for r in rows if r.get("reference_flips")]
    exact = sum(len(r["reference_flips"]) for r in found)
    back = sum(len(r["reference_flips"]) == 2 for r in found)
    worst = max(r["relative_error"] for r in found)
    assert f"{len(found)} of the {len(rows)} have such a flip" in page
    within = f"{worst:.1e}".replace("e-0", "e-")
    assert f"all {exact} flips of the reference are labelled, within {within}" in page
    assert back == 2 and "two of them where the multiplier comes back through -1" in page
    assert flips["figures"]["unexplained_flips"] == 0 and flips["figures"]["errors"] == 0


def _declared(system: str, *, tight: bool = False) -> dict:
    """The newest ``benchmarks/declared_branch.py`` record of ``system`` that continued its
    default range (not a stored branch): at the default knobs, or (``tight``) at
    ``--rtol 1e-11 --tolerance 5e-9``."""
    runs = [
        r["figures"]
        for r in records("declared_branch.py")
        if r["figures"]["system"] == system
        and not r["figures"]["branch_file"]
        and ("--rtol 1e-11 --tolerance 5e-9" in r["command"]) == tight
        and "--stop" not in r["command"]
        and "--start" not in r["command"]
    ]
    return runs[-1]


def _declared_summary(fig: dict) -> str:
    """How the page sums up a declared branch's record."""
    resolved = [b for b in fig["labels"] if b["resolved"]]
    return (
        f"the branch reached {fig['reached']:.4f} rad/s and ended at {fig['ended_at']:.4f} "
        f"({fig['points']} points, {fig['cpu']:.0f} s of CPU); {len(resolved)} of its "
        f"{len(fig['labels'])} labels are resolved and {fig['confirmed']} of those confirmed "
        "by simulation"
    )


@pytest.mark.parametrize("system", ["fourbar", "slider_crank"])
def test_the_declared_branches_are_their_newest_records(system):
    """docs/continuation.md, "Declared mechanisms, every label checked by simulation": the
    newest ``benchmarks/declared_branch.py`` record of each system (its default range and
    knobs): how far the branch reached, at what cost, how many labels are resolved and how many
    of those confirmed by simulation, each label's value, and the noise where Newton's tolerance
    was raised."""
    page = " ".join(_page("continuation.md").split())
    fig = _declared(system)
    assert f"`python benchmarks/declared_branch.py --system {system}`" in page
    summary = _declared_summary(fig)
    assert summary in page, summary
    # a confirmed label is a resolved one (the page counts "of those")
    assert all(c["resolved"] for c in fig["checks"] if c["confirmed"])
    for b in fig["labels"]:
        # every resolved label's value to 1e-7 rad/s, an unresolved one's to 1e-5
        assert (f"{b['value']:.7f}" if b["resolved"] else f"{b['value']:.5f}") in page, b
    raised = re.search(r"noise there ([\d.e+-]+)", fig["tolerance_raised"])
    assert f"{_g(raised[1])} (scaled)" in page


def test_the_slider_crank_s_labels_move_with_the_knobs_as_the_page_says():
    """docs/continuation.md: the slider-crank's branch at the default knobs and at rtol 1e-11
    with Newton's tolerance 5e-9: the same labels in the same order; how far each moved; the
    lift-off's margin slope and the placement its uncertainty allows."""
    page = " ".join(_page("continuation.md").split())
    base, tight = _declared("slider_crank"), _declared("slider_crank", tight=True)
    assert [b["type"] for b in base["labels"]] == [b["type"] for b in tight["labels"]]
    moves = [
        abs(a["value"] - b["value"]) for a, b in zip(base["labels"], tight["labels"], strict=True)
    ]
    rest = moves[1:]
    said = (
        f"the located values move by {_g(f'{min(rest):.1g}')} to {max(rest):.2g} rad/s, except the "
        f"lift-off's, by {moves[0]:.2g} rad/s"
    )
    assert said in page, said
    before = base["checks"][0]["before"]
    slope = abs(before["margin"]) / before["distance_from_label"]
    uncertainty = base["uncertainty"]
    said = (
        f"its margin grows by {_g(f'{slope:.2g}')} m per rad/s, so the default orbit's "
        f"uncertainty of {_g(f'{uncertainty:.2g}')} m"
    )
    assert said in page, said
    assert f"to some {base['uncertainty'] / slope:.1g} rad/s" in page
    assert f", {tight['cpu']:.0f} s of CPU)" in page
    now = sum(
        a["resolved"] < b["resolved"] for a, b in zip(base["labels"], tight["labels"], strict=True)
    )
    assert f"{now} of the {base['unresolved']} unresolved ones" in page


def test_the_four_bar_s_grazing_types_are_the_newest_record_s():
    """docs/continuation.md, the four-bar: which grazings are `persistent` and which
    `persistent_flip`, the unlabelled return of the multiplier after the first flip (the
    distance of the stable orbit past it), and the border collision left unconfirmed."""
    page = " ".join(_page("continuation.md").split())
    fig = _declared("fourbar")
    grazings = [c for c in fig["checks"] if c["type"] == "grazing"]
    types = {f"{b['value']:.7f}": b["transition"] for b in fig["labels"]}
    steady = [c for c in grazings if types[f"{c['omega']:.7f}"] == "persistent"]
    flips = [c for c in grazings if types[f"{c['omega']:.7f}"] == "persistent_flip"]
    said = "The grazings at " + ", ".join(
        f"{c['omega']:.7f} ({c['before']['branch_events']:g} -> {c['after']['branch_events']:g}"
        + (" events per period)" if i == 0 else ")")
        for i, c in enumerate(steady[:-1])
    )
    said += f" and {steady[-1]['omega']:.7f} ({steady[-1]['before']['branch_events']:g} -> "
    said += f"{steady[-1]['after']['branch_events']:g}) are `persistent`"
    assert said in page, said
    assert all(c["before"]["stable"] and c["after"]["stable"] for c in steady)
    first, second = flips
    assert not second["after"]["stable"] and second["after"]["simulated_period"] == 2
    assert f"At {second['omega']:.7f} (16 -> 18) the orbit past the grazing is unstable" in page
    # the first flip and the doubling that brings the multiplier back: no orbit between them
    back = fig["checks"][fig["checks"].index(first) + 1]
    assert back["type"] == "period_doubling" and "after" not in first and "before" not in back
    assert first["before"]["stable"] and back["after"]["stable"]
    assert not first["confirmed"] and not back["confirmed"]
    said = (
        f"The grazing at {first['omega']:.7f} (8 -> 16) is typed `persistent_flip` too, and the "
        f"period doubling at {back['omega']:.7f} brings the multiplier back inside; the "
        f"simulation confirms the orbits stable {first['before']['distance_from_label']:.2g} "
        f"rad/s before the grazing and {back['after']['distance_from_label']:.2g} rad/s after "
        "the doubling"
    )
    assert said in page, said
    end = [c for c in grazings if types[f"{c['omega']:.7f}"] == "border_collision"]
    assert len(end) == 1 and not end[0]["confirmed"] and "after" not in end[0]
    assert f"The border collision at {end[0]['omega']:.7f}" in page
