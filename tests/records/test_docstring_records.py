"""What the code's docstrings, comments and messages may quote. Docstrings describe: what a
function does, its parameters, units, references and an example; the measured evidence (each
figure with its record or test) lives in the docs pages, whose figures
tests/records/test_doc_records.py
and the pages' tests check. So the package names no commit, the figures moved out of its
docstrings stay out, and what remains is checked here: the compile notice (a message, built from
its record), cross-references, arithmetic and the one docstring outside this project's part of
the package that still quotes a record (models/_reduced.py's ``spd4_solve``)."""

import importlib
import inspect
import json
import os
import re
from types import SimpleNamespace

from _records import NOTES, ROOT

from workbench.analysis import _benettin, _embedding, _lyapunov, _surrogate
from workbench.campaign import _jobqueue, _warm
from workbench.cli import _console
from workbench.continuation import _exponent, _strobe
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


# -- workbench/continuation/_exponent.py ----------------------------------------------------------
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


# -- arithmetic --------------------------------------------------------------------------------
def test_the_surrogate_comment_s_arithmetic():
    """The comment on the surrogate test's ``MAX_SAMPLES`` factors 100 001 and counts 16 384
    samples at 10 000 per cycle as 1.6 cycles."""
    comment = _comment(_surrogate, "MAX_SAMPLES")
    assert "such as 100 001 = 11 x 9091," in comment and 11 * 9091 == 100_001
    assert "first 16 384 samples, 1.6 cycles," in comment and round(16_384 / 10_000, 1) == 1.6


def test_the_figures_are_gone():
    """The figures that no record and no test backed (measured once by hand, or remembered), and
    those that moved to the docs pages with their records and tests, stay out of the docstrings
    and comments they were in."""
    gone = {
        _flat(inspect.getsource(_console)): ["30-95", "28-95", "15-40"],
        _doc(_benettin.lle_from_equations): ["-75.9", "3.3e4", "~0 1/s", "~6.6", "44 %", "8 %"]
        + ["25.66", "-67.9", "-74.2", "6.2-6.8", "3555", "tests/", "benchmarks/"],
        _comment(_benettin, "SEPARATION"): ["+4.0", "+4.9", "+4.5", "benchmarks/"],
        _doc(_exponent): ["314", "398", "27 %", "0.2 %", "35 %", "-76", "~1e-5", "25 %", "8 %"]
        + ["3.34e4", "-67.9", "-74.2", "-3.8", "tests/", "benchmarks/"],
        _doc(_strobe): ["30 885", "8 163", "7 998", "tests/"],
        _doc(_jobqueue): ["30-90"],
        _doc(_exponent.floquet_exponent): ["workbench.continuation.NewtonFailure"],
        _doc(_embedding.embedding_fnn): ["0.029", "-69 %", "-0.4 %", "10 %", "tests/"],
        _doc(_embedding.embedding_cao): ["0.81", "0.98", "0.13", "16 series"],
        _comment(_surrogate, "MAX_SAMPLES"): ["s of CPU", "4 s cut", "1.4-3.4"],
        _comment(_lyapunov, "DEFECT"): ["63 030", "1.8e6", "about 3 times", "0.01 1/s"]
        + ["5.6e6", "736 780", "2.8e-2", "47 770", "2.9e-4", "benchmarks/"],
        _doc(_radau): ["tests/"],
        _comment(_radau, "THETA_KEEP_ANALYTIC"): ["20 %", "15-50 %"],
        _comment(_radau, "EXPLICIT_TRIGGER"): ["3.9-4.1"],
        _doc(_radau.newton_limit): ["2 of"],
        _doc(_friction_report): ["139", "20 times"],
        _doc(_reduced.lugre_diagnostic): ["20 times"],
        _doc(_reduced.spd4_solve): ["0.33"],
        _doc(_study): ["~200", "README", "25.66", "benchmarks/"],
        _doc(_ensemble): ["10-500", "25.66", "benchmarks/"],
        _comment(_numbers, "EXPONENT_CYCLES"): ["28.4", "7.9", "25.2-29.5", "issue 24"]
        + ["23.6", "25.66", "tests/", "benchmarks/"],
    }
    for text, figures in gone.items():
        for figure in figures:
            assert figure not in text, (figure, text[:80])


# -- no commit ids in the package ----------------------------------------------------------------
#: a short or full git commit id (7-40 hex digits with a letter and a digit, optionally
#: "-dirty"), standing alone: not part of a longer word, a number or a float's digits
COMMIT_ID = re.compile(
    r"(?<![\w.])(?=[0-9a-f]*[a-f])(?=[0-9a-f]*[0-9])[0-9a-f]{7,40}(?:-dirty)?(?![\w])"
)


def test_the_package_source_names_no_commit():
    """The package's source (docstrings, comments, messages) names no commit: which commit a
    figure was measured at is the docs pages' and the benchmark records' business."""
    assert COMMIT_ID.search("the record at 2e994d4-dirty") and COMMIT_ID.search("(cf87888)")
    assert not COMMIT_ID.search("2.220446049250313e-16 0x7fffffff deadbeef")
    found = [
        f"{path.relative_to(ROOT)}:{n}: {m[0]}"
        for path in sorted((ROOT / "workbench").rglob("*.py"))
        for n, line in enumerate(path.read_text().splitlines(), 1)
        for m in COMMIT_ID.finditer(line)
    ]
    assert not found, found
