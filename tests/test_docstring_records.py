"""The numbers the code's docstrings, comments and messages quote (the project's rule: the docs,
docstrings included, quote only what the code produces now, and a test checks each number).
Each test reads the docstring (or the comment above a constant) and the benchmark record or the
test it names and asserts that they agree: a current figure is the newest record of its
benchmark, a "before" figure the record the docstring names, a tested figure the value its test
asserts. The helpers that read the benchmarks' records (benchmarks/records/) and the
measurements made by hand (benchmarks/NOTES.md) are tests/test_doc_records.py's."""

import importlib
import inspect
import json
import math
import os
import re
from types import SimpleNamespace

from test_doc_records import (
    BEFORE_SHRINK_SCANS,
    NOTES,
    ROOT,
    _chaos_numbers,
    _e,
    _n,
    _newest,
    _tangent_records,
    chaos_records,
    defect_record,
    records,
    scan_means,
)

from workbench.analysis import _benettin, _embedding, _lyapunov, _surrogate
from workbench.campaign import _warm
from workbench.cli import _console
from workbench.continuation import _exponent
from workbench.models import _friction_report, _reduced
from workbench.precision import _study
from workbench.run import _ensemble
from workbench.solver import _radau
from workbench.study import _numbers


def _flat(text: str) -> str:
    """Text with its whitespace collapsed."""
    return " ".join(text.split())


def _doc(obj) -> str:
    """A module's, function's or compiled function's docstring, whitespace collapsed."""
    return _flat(inspect.getdoc(getattr(obj, "py_func", obj)))


def _comment(module, name: str) -> str:
    """The ``#`` / ``#:`` comment right above ``name = ...`` in a module, whitespace collapsed."""
    lines = inspect.getsource(module).splitlines()
    i = next(k for k, line in enumerate(lines) if line.startswith(f"{name} ="))
    block = []
    while lines[i - 1].startswith("#"):
        i -= 1
        block.insert(0, lines[i].removeprefix("#:").removeprefix("#"))
    return _flat(" ".join(block))


def _test_source(path: str, name: str) -> str:
    """The source of one test function of tests/``path`` (up to the next top-level def)."""
    source = (ROOT / "tests" / path).read_text()
    return re.split(r"\n(?:@|def )", source.split(f"def {name}(")[1])[0]


def _chaos_record() -> dict:
    """The newest ``benchmarks/lle.py --chaos`` record."""
    return chaos_records()[-1]


def _contracting_orbit_test() -> tuple[str, str]:
    """-67.9 and -74.2 1/s: the two-trajectory and variational exponents of the nine-bar's stable
    orbit that tests/test_lyapunov.py asserts."""
    test = _test_source(
        "test_lyapunov.py", "test_contracting_nine_bar_orbit_reads_a_negative_exponent"
    )
    assert "with_parameters(omega=0.5 * math.pi, clearance=2e-5)" in test
    return re.search(
        r"assert abs\(float\(r\.lle\) - (-[\d.]+)\) < [\d.]+ and "
        r"abs\(float\(r\.lle_variational\) - (-[\d.]+)\) < [\d.]+",
        test,
    ).groups()


# -- workbench/cli/_console.py --------------------------------------------------------------------
def test_the_compile_notice_quotes_the_compile_record(monkeypatch, capsys):
    """The notice before a first compile quotes the record ``benchmarks/cache.py`` wrote
    (workbench/campaign/compile_times.json: a first run's CPU and wall time with an empty cache,
    the machine's cores and load) of the model, else Duffing's, naming it (issue 40: it quoted
    28-95 s where a first run took 264 s of wall and 137 s of CPU time at a load of 4-5)."""
    records = json.loads(_warm.COMPILE_TIMES.read_text())
    assert {"duffing", "ninebar", "slider_crank"} <= set(records)
    for model, r in records.items():
        assert r["command"].startswith(f"python benchmarks/cache.py --model {model}"), r
        assert 0 < r["cpu_seconds"] and r["wall_seconds"] >= r["cpu_seconds"] / r["cores"], r
        assert re.fullmatch(r"[0-9a-f]{7,}(-dirty)?", r["commit"]) and len(r["load"]) == 2, r

    monkeypatch.setattr(_warm, "kernel_cached", lambda scene: False)
    monkeypatch.setattr(_warm, "load_kernel", lambda toml: None)
    monkeypatch.setattr(os, "getloadavg", lambda: (5.2, 4.0, 3.0))  # this machine's, now
    for model, measured in [
        ("ninebar", "ninebar"),
        ("slider_crank", "slider_crank"),
        ("duffing", "duffing"),
        ("lorenz", "duffing"),
    ]:
        r = records[measured]
        _console.compile_kernel(SimpleNamespace(model=model, sweep={}, to_toml=lambda: ""))
        notice = capsys.readouterr().err.splitlines()[0]
        low, high = sorted(round(x) for x in r["load"])
        load = f"{low}" if low == high else f"{low}-{high}"
        which = "" if measured == model else f" for the {measured} kernel"
        assert (
            f"compiling the {model} kernel (first run only; measured{which} on a "
            f"{r['cores']}-core machine at a load of {load}: {r['cpu_seconds']:.0f} s of CPU, "
            f"{r['wall_seconds']:.0f} s wall, the wall time growing with the machine's load, "
            "now 5; later runs load it from the cache)"
        ) == notice


# -- workbench/analysis/_benettin.py and the chaos case's exponent --------------------------------
def test_lle_from_equations_quotes_the_lle_records_and_its_test():
    """``lle_from_equations``: the decorrelation time from the newest ``--chaos`` record's
    exponent, the stable orbit's exponents from tests/test_lyapunov.py, the noise floor before
    (the ``--scan`` records docs/analysis.md names) and now (the newest ``--scan`` record of each
    command), the shrinkages from the newest ``--chaos`` record."""
    doc = _doc(_benettin.lle_from_equations)
    chaos = _chaos_record()
    lle = _chaos_numbers(chaos)[0]
    decorrelation = f"{math.log(1e9) / float(lle):.1f}"
    assert (
        f"(ln(1/1e-9) / λ, {decorrelation} s on the chaos case at its λ = {lle} 1/s: the newest "
        f"``benchmarks/lle.py --chaos`` record, at {chaos['commit']}, rtol 1e-6)"
    ) in doc

    copies, variational = _contracting_orbit_test()
    assert (
        f"they now read {copies} 1/s over one cycle against {variational} 1/s for the variational "
        "exponent on the same trajectory (tests/test_lyapunov.py)"
    ) in doc

    before, newest = [], {}  # the means at d0 = 1e-10; the newest record of each scan command
    for record in records("lle.py"):
        if "--scan" not in record["command"]:
            continue
        means = list(scan_means(record, 1e-10).values())
        if record["commit"] in BEFORE_SHRINK_SCANS:
            before += means
        newest[record["command"]] = (record["commit"], means)
    assert len(before) == 4 and len(newest) == 3  # rtol 1e-6 free and capped, 1e-8, 1e-10
    (commit,) = {c for c, _ in newest.values()}
    now = [m for _, means in newest.values() for m in means]
    assert len(now) == 4
    assert (
        f"the noise floor at d0 = 1e-10 fell from +{min(before):.1f}-{max(before):.1f} 1/s, the "
        f"``benchmarks/lle.py --scan`` records at {BEFORE_SHRINK_SCANS[0]}, "
        f"{BEFORE_SHRINK_SCANS[1]} and {BEFORE_SHRINK_SCANS[2]}, to "
        f"{min(now):.0f}-{max(now):.0f} 1/s, the newest, at {commit};"
    ) in doc

    call = chaos["figures"]["1e-06"]
    total, shrunk = call["renormalisations"][0], call["shrink_renormalisations"][0]
    assert (
        f"at rtol 1e-6, {shrunk} of {total} renormalisations were shrinkages, the ``--chaos`` "
        f"record at {chaos['commit']};"
    ) in doc


def test_the_chaos_case_exponent_in_the_docstrings_is_the_newest_lle_record():
    """The chaos case's exponent that the ensemble, the work-precision study and the study's
    exponent windows quote: the newest ``benchmarks/lle.py --chaos`` record at rtol 1e-6; the
    3-cycle window's, the value tests/test_lyapunov.py asserts."""
    chaos = _chaos_record()
    lle, err = _chaos_numbers(chaos)[:2]
    record = f"the newest ``benchmarks/lle.py --chaos`` record, at {chaos['commit']}"
    assert f"(largest Lyapunov exponent {lle} 1/s on the nine-bar's chaos case: {record})" in (
        _doc(_ensemble)
    )
    call = chaos["figures"]["1e-06"]
    assert (call["starts"], call["cycles_per_start"], call["converged"]) == (4, 20, True)

    study = _doc(_study)
    assert f"separate at tens of 1/s or more (the nine-bar's chaos case: {lle} 1/s, {record})" in (
        study
    )
    assert "docs/accuracy.md" in study and "README" not in study
    assert (ROOT / "docs" / "accuracy.md").read_text().startswith("# Accuracy and cost\n")

    test = _test_source("test_lyapunov.py", "test_chaos_case_two_trajectory_and_variational_agree")
    assert '"cycles": 3' in test
    short, short_err = re.search(
        r"assert agrees\(float\(r\.lle\), float\(r\.stderr\), ([\d.]+), ([\d.]+)\)", test
    ).groups()
    assert (
        f"over 3 cycles the chaos case read {short} +/- {short_err} 1/s, tests/test_lyapunov.py; "
        f"over 4 x 20 cycles {lle} +/- {err} at rtol 1e-6, the newest benchmarks/lle.py --chaos "
        f"record, at {chaos['commit']};"
    ) in _comment(_numbers, "EXPONENT_CYCLES")


# -- workbench/continuation/_exponent.py ----------------------------------------------------------
def test_the_point_exponent_docstring_quotes_its_record_and_tests():
    """The module docstring of continuation/_exponent.py: the noise's rate before, from the
    ``benchmarks/continuation.py --parts chaos_maps`` record it names; the stable orbit's
    exponents from tests/test_lyapunov.py; its Floquet bound from tests/test_continuation.py."""
    doc = _doc(_exponent)
    # the "before" figure: the oldest chaos_maps record (two-trajectory copies on that orbit;
    # later records give its Floquet bound)
    oldest = next(r for r in records("continuation.py") if "--parts chaos_maps" in r["command"])
    corner = oldest["figures"]["chaos_map_corners"][
        "omega_clearance at omega=1.571, clearance=2e-05"
    ]
    mantissa, exponent = f"{corner['lle']:.3g}".split("e")
    assert (
        f"the nine-bar's omega = 0.5 pi, c = 20 um read {mantissa}e{int(exponent)} +- "
        f"{corner['lle_stderr']:.2g} 1/s, the noise's rate: the ``benchmarks/continuation.py "
        f"--parts chaos_maps`` record at {oldest['commit']})"
    ) in doc
    copies, variational = _contracting_orbit_test()
    assert (
        f"it now reads {copies} 1/s over one cycle there, against {variational} 1/s for the "
        "variational exponent on the same trajectory (tests/test_lyapunov.py)"
    ) in doc

    bound_test = _test_source(
        "test_continuation.py",
        "test_a_contracting_nine_bar_orbit_gets_a_floquet_bound_not_the_noise_rate",
    )
    assert "with_parameters(omega=0.5 * math.pi, clearance=2e-5)" in bound_test
    bound = re.search(r"assert abs\(float\(ind\.lle\) - (-[\d.]+)\) <", bound_test)[1]
    assert f"the bound is {bound} 1/s (tests/test_continuation.py)" in doc

    # the copies' and the tangent vector's readings on the chaotic nine-bar: on the page
    # (docs/continuation.md, checked by tests/test_continuation.py), not in the docstring
    assert "docs/continuation.md" in doc and "36.1" not in doc


def test_the_exponent_docstrings_name_what_exists():
    """Every qualified cross-reference of continuation/_exponent.py's docstrings names an object
    that exists (``NewtonFailure`` lives in workbench.continuation._newton)."""
    docs = [inspect.getdoc(_exponent)] + [
        inspect.getdoc(f) or ""
        for _, f in inspect.getmembers(_exponent, inspect.isfunction)
        if f.__module__ == _exponent.__name__
    ]
    refs = {m for doc in docs for m in re.findall(r":\w+:`~?(workbench\.[\w.]+)`", doc)}
    assert "workbench.continuation._newton.NewtonFailure" in refs
    for ref in refs:
        module, _, name = ref.rpartition(".")
        assert hasattr(importlib.import_module(module), name), ref


# -- workbench/analysis/_lyapunov.py --------------------------------------------------------------
def test_the_defect_comment_quotes_the_tangent_speed_records():
    """The comment on ``DEFECT``: the defect's cost from the hand-written section of
    benchmarks/RESULTS.md it names, the sum checks and steps from the newest tangent_speed
    record of each window, with their commits (as docs/analysis.md quotes them)."""
    comment = _comment(_lyapunov, "DEFECT")
    section, measured_at, d10, d1 = defect_record()
    assert (
        f"(chaos case, 8 exponents over 0.1 cycle, rtol 1e-6: D = 1 took {d1} steps per cycle "
        f'against {d10} at D = 10, measured at {measured_at}: benchmarks/RESULTS.md, "{section}")'
    ) in comment

    records = _tangent_records()
    rel = {}
    for key, window in {
        "2 cycles": ("2", "1e-06", "10"),
        "2 cycles tight": ("2", "1e-08", "10"),
        "defect 3": ("0.5", "1e-06", "3"),
        "defect 3 tight": ("0.5", "1e-08", "3"),
        "default defect": ("0.5", "1e-06", "10"),
    }.items():
        r = _newest(records, *window, "m = 4")
        rel[key] = (_e(r["rows"]["m = 4"][9]), r["commit"], _n(r["rows"]["m = 4"][2]))
    assert (
        f"4 exponents over 2 cycles closed to {rel['2 cycles'][0]} at rtol 1e-6 and "
        f"{rel['2 cycles tight'][0]} at 1e-8 (at {rel['2 cycles'][1]} and "
        f"{rel['2 cycles tight'][1]})"
    ) in comment
    assert rel["defect 3"][1] == rel["defect 3 tight"][1]
    assert (
        f"with D = 3 over 0.5 cycles to {rel['defect 3'][0]} and {rel['defect 3 tight'][0]} (at "
        f"{rel['defect 3'][1]}), for {rel['defect 3'][2]} steps per cycle at rtol 1e-6 against "
        f"{rel['default defect'][2]} at D = 10 (at {rel['default defect'][1]})"
    ) in comment
    all8 = _newest(records, "2", "1e-06", "10", "m = 8")
    assert (
        f"closes at rtol 1e-6 ({_e(all8['rows']['m = 8'][9])} over 2 cycles, at {all8['commit']})"
    ) in comment


# -- workbench/models/_reduced.py -----------------------------------------------------------------
def test_the_block_solve_quotes_the_evaluation_cost_record():
    """``spd4_solve``: the unrolled Cholesky factorisation's cost from the hand-written "Cost of
    an evaluation" of the "Before 0.2.0" section it names (benchmarks/NOTES.md, which
    benchmarks/RESULTS.md shows)."""
    text = _flat(NOTES.read_text())
    before = text.split("## Before 0.2.0: the measurements the README carried")[1]
    cost = before.split("**Cost of an evaluation.**")[1].split("**")[0]
    us = re.search(
        r"unrolled Cholesky factorisation chains four square roots and ten divisions "
        r"and cost ([\d.]+) us",
        cost,
    )[1]
    assert (
        f"four square roots and ten divisions, and cost {us} us: benchmarks/RESULTS.md, "
        '"Before 0.2.0", "Cost of an evaluation")'
    ) in _doc(_reduced.spd4_solve)


# -- figures a test checks, or arithmetic ---------------------------------------------------------
def test_the_embedding_and_surrogate_figures_are_their_tests_and_arithmetic():
    """``embedding_fnn`` cites the bound tests/test_wolf_heldout.py holds a Duffing section's
    estimate to; the surrogate test's comment factors 100 001 and counts 16 384 samples at
    10 000 per cycle as 1.6 cycles."""
    test = _test_source("test_wolf_heldout.py", "test_heldout_duffing_section")
    assert "assert float(r.lle) == pytest.approx(per_period, rel=FLOW_GROSS)" in test
    source = (ROOT / "tests" / "test_wolf_heldout.py").read_text()
    rel = float(
        re.search(r"^FLOW_BOUND, FLOW_GROSS, FLOW_MISSES = [\d.]+, ([\d.]+),", source, re.M)[1]
    )
    assert (
        f"in the plateau's first dimension a Duffing section's estimate is within {rel * 100:.0f} "
        "% of the exponent: tests/test_wolf_heldout.py.)"
    ) in _doc(_embedding.embedding_fnn)
    comment = _comment(_surrogate, "MAX_SAMPLES")
    assert "such as 100 001 = 11 x 9091," in comment and 11 * 9091 == 100_001
    assert "first 16 384 samples, 1.6 cycles," in comment and round(16_384 / 10_000, 1) == 1.6


def test_the_unrecorded_figures_are_gone():
    """The figures that no record and no test backed (measured once by hand, or remembered) stay
    out of the docstrings and comments they were in."""
    gone = {
        _flat(inspect.getsource(_console)): ["30-95", "28-95", "15-40"],
        _doc(_benettin.lle_from_equations): ["-75.9", "3.3e4", "~0 1/s", "~6.6", "44 %", "8 %"],
        _doc(_exponent): ["314", "398", "27 %", "0.2 %", "35 %", "-76", "~1e-5", "25 %", "8 %"],
        _doc(_exponent.floquet_exponent): ["workbench.continuation.NewtonFailure"],
        _doc(_embedding.embedding_fnn): ["0.029", "-69 %", "-0.4 %"],
        _doc(_embedding.embedding_cao): ["0.81", "0.98", "0.13", "16 series"],
        _comment(_surrogate, "MAX_SAMPLES"): ["s of CPU", "4 s cut", "1.4-3.4"],
        _comment(_lyapunov, "DEFECT"): ["63 030", "1.8e6", "about 3 times", "0.01 1/s"],
        _comment(_radau, "THETA_KEEP_ANALYTIC"): ["20 %", "15-50 %"],
        _comment(_radau, "EXPLICIT_TRIGGER"): ["3.9-4.1"],
        _doc(_radau.newton_limit): ["2 of"],
        _doc(_friction_report): ["139", "20 times"],
        _doc(_reduced.lugre_diagnostic): ["20 times"],
        _doc(_reduced.spd4_solve): ["0.33"],
        _doc(_study): ["~200", "README"],
        _doc(_ensemble): ["10-500"],
        _comment(_numbers, "EXPONENT_CYCLES"): ["28.4", "7.9", "25.2-29.5", "issue 24"],
    }
    for text, figures in gone.items():
        for figure in figures:
            assert figure not in text, (figure, text[:80])
