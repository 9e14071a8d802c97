"""What a user reads matches what the code does: command-line help against the code's defaults,
module texts against the package's layers and exports, docstrings against signatures, and the
behaviours those texts describe (``periodic_orbit``'s ``max_iterations``, ``workbench campaign``'s
options with a continued sweep and its dashboard notice)."""

from __future__ import annotations

import argparse
import importlib
import inspect
import pkgutil
import re
from pathlib import Path

import pytest

import workbench
from workbench.cli import build_parser, main

DUFFING_SWEEP = {
    "model": {"name": "duffing"},
    "run": {"cycles": 2, "transient_cycles": 1},
    "record": {"samples_per_period": 1},
    "sweep": {"gamma": [0.3, 0.4]},
}


def _command(name: str) -> argparse.ArgumentParser:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[name]


def _option(command: str, option: str) -> argparse.Action:
    return next(a for a in _command(command)._actions if option in a.option_strings)


def _scene_file(tmp_path: Path, data: dict) -> str:
    path = tmp_path / "scene.toml"
    path.write_text(workbench.load_scene(data).to_toml())
    return str(path)


# -- 1. command-line help names the defaults the code uses ------------------------------------


def test_accuracy_help_names_the_default_methods_and_tolerances():
    from workbench.precision import DEFAULT_METHODS, DEFAULT_TOLERANCES

    assert f"(default: {','.join(DEFAULT_METHODS)})" in _option("accuracy", "--methods").help
    first, last = re.search(
        r"\(default (\S+)\.\.(\S+)\)", _option("accuracy", "--tolerances").help
    ).groups()
    assert (float(first), float(last)) == (DEFAULT_TOLERANCES[0], DEFAULT_TOLERANCES[-1])


def test_campaign_help_names_the_default_limit_of_points():
    from workbench.campaign._grid import MAX_POINTS

    assert f"(default {MAX_POINTS};" in _option("campaign", "--max-points").help


def test_every_numeric_default_in_a_help_text_is_the_options_default():
    """An option whose help says ``(default X)`` with X a number (or numbers, comma-separated)
    and that has a default in code: the two agree."""
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    checked = 0
    for command, parser in sub.choices.items():
        for action in parser._actions:
            stated = re.search(r"\(default:? ([^)]*)\)", action.help or "")
            if stated is None or action.default in (None, argparse.SUPPRESS):
                continue
            numbers = re.match(r"[-+0-9.e,]+", stated.group(1))
            if numbers is None:
                continue
            values = [float(v) for v in numbers.group(0).split(",")]
            code = action.default if isinstance(action.default, list) else [action.default]
            assert values == [float(v) for v in code], (command, action.option_strings)
            checked += 1
    assert checked >= 5


# -- 2. workbench campaign: --max-memory with a continued sweep; -q and the dashboard notice ----


def test_campaign_refuses_max_memory_with_a_continued_sweep(tmp_path, capsys):
    path = _scene_file(
        tmp_path, dict(DUFFING_SWEEP, sweep={**DUFFING_SWEEP["sweep"], "continuation": "up"})
    )
    out = tmp_path / "c.nc"
    assert main(["campaign", path, "-o", str(out), "--max-memory", "1GiB", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "--max-memory 1 GiB: a continued sweep ([sweep] continuation)" in err
    assert "drop --max-memory" in err
    assert not out.exists() and not Path(f"{out}.blocks").exists()  # refused before any work
    assert "not with [sweep] continuation" in _option("campaign", "--max-memory").help


def test_campaign_dashboard_notice_once_without_quiet_and_never_with_it(tmp_path, capsys):
    """``-q``: no notices (the dashboard link is one); without it the link is printed once."""
    distributed = pytest.importorskip("distributed")
    path = _scene_file(tmp_path, DUFFING_SWEEP)
    out = str(tmp_path / "c.nc")
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0"
    ) as cluster:
        argv = ["campaign", path, "-o", out, "--restart", "--scheduler", cluster.scheduler_address]
        assert main(argv + ["-q"]) == 0
        assert "dashboard" not in capsys.readouterr().err
        assert main(argv) == 0
        assert capsys.readouterr().err.count("dask dashboard at ") == 1
    assert "no notices" in _option("campaign", "-q").help


# -- 3. periodic_orbit's max_iterations limits Newton's method ---------------------------------

ORBIT = {"model": {"name": "duffing"}, "parameters": {"gamma": 0.2}, "run": {"transient_cycles": 0}}


def test_periodic_orbit_max_iterations_limits_newton_and_is_recorded():
    from workbench.continuation import periodic_orbit

    with pytest.raises(RuntimeError, match=r"did not converge .* in 2 iterations"):
        periodic_orbit(ORBIT, max_iterations=2)  # from the initial state: needs about 6
    r = periodic_orbit(ORBIT, max_iterations=40, tolerance=1e-9)
    assert 2 < int(r.newton_iterations[0]) <= 40 and float(r.residual[0]) < 1e-9
    assert r.attrs["max_iterations"] == 40 and r.attrs["tolerance"] == 1e-9
    assert "max_points" not in r.attrs  # a branch's setting, not one orbit's
    doc = inspect.getdoc(periodic_orbit)
    assert re.search(r"^max_iterations : int$", doc, re.M)


@pytest.mark.parametrize("bad", [-1, 2.5, True, "30"])
def test_periodic_orbit_refuses_a_bad_max_iterations(bad):
    from workbench.continuation import periodic_orbit

    with pytest.raises(ValueError, match=rf"max_iterations={re.escape(repr(bad))}: must be a non"):
        periodic_orbit(ORBIT, max_iterations=bad)


# -- 4-6. no measurement cited that no page holds ----------------------------------------------


@pytest.mark.parametrize(
    "module",
    [
        "workbench.archive._netcdf",
        "workbench.campaign",
        "workbench.campaign._store",
        "workbench.campaign._execute",
    ],
)
def test_block_file_and_pool_texts_cite_no_missing_measurement(module):
    text = inspect.getsource(importlib.import_module(module))
    assert 'README, "Campaigns"' not in text and '"Campaigns")' not in text
    assert "a third of the write time" not in text and "half the write time" not in text


# -- 7. the layers as the package's texts give them ---------------------------------------------


def test_package_docstring_lists_the_layers_in_order():
    from workbench._layers import LAYERS

    text = " ".join(workbench.__doc__.split())
    chain = re.search(r"(solver ->.*?-> cli)", text).group(1)
    named = [re.sub(r"\(.*?\)", "", part).strip() for part in chain.split("->")]
    assert named == [name for name, _ in LAYERS if name != "base"]


def test_continuation_docstring_places_it_directly_above_campaign():
    import workbench.continuation
    from workbench._layers import LAYERS

    names = [name for name, _ in LAYERS]
    assert names.index("continuation") == names.index("campaign") + 1
    text = " ".join(workbench.continuation.__doc__.split())
    assert "directly above campaign" in text and "beside campaign" not in text


# -- 8, 12. workbench.plot: what returns a figure; the marks of a branch -------------------------


def test_plot_docstring_names_every_function_that_returns_no_figure():
    import workbench.plot as plot

    for name in plot.__all__:
        obj = getattr(plot, name)
        if not inspect.isfunction(obj) or name.endswith("_figure") or name == "run_figures":
            continue
        assert f":func:`{name}`" in plot.__doc__, name


def test_branch_figure_docstring_names_every_label_mark():
    from workbench.plot import LABEL_MARKS, branch_figure

    doc = " ".join(inspect.getdoc(branch_figure).replace("-", " ").split())
    for kind, (_, short, _) in LABEL_MARKS.items():
        assert f"{short} {kind.replace('_', ' ')}".lower() in doc.lower(), kind


# -- 9, 10. verify's record interval, study's report -------------------------------------------


def test_verify_record_dt_help_gives_both_defaults():
    text = _option("verify", "--record-dt").help
    assert "coarsest step for a scene with clearance joints" in text and "else 1e-3" in text


def test_study_help_says_where_the_report_goes(tmp_path, monkeypatch):
    import workbench.study._spec as spec

    command = _command("study")
    description = " ".join(command.description.split())
    assert "studies/REPORT.md in a repository checkout" in description
    assert "OUTPUT/REPORT.md" in description
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    short = next(a.help for a in sub._choices_actions if a.dest == "study")
    assert "'report' writes the report" in short and "studies/REPORT.md" not in short
    assert spec.report_path(tmp_path) == spec.REPOSITORY_STUDIES / "REPORT.md"  # this checkout
    monkeypatch.setattr(spec, "STUDIES_DIR", tmp_path / "installed" / "scenes")
    assert spec.report_path(tmp_path / "out") == tmp_path / "out" / "REPORT.md"


# -- 11. cross-references resolve -------------------------------------------------------------


def _resolves(path: str) -> bool:
    parts = path.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for attr in parts[i:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def test_every_cross_reference_to_a_workbench_object_resolves():
    """Each ``:func:`workbench....``` (class, data, mod, ...) in the package's source names an
    object that exists at that path."""
    role = re.compile(r":(?:func|class|data|mod|meth|attr|exc):`~?(workbench\.[\w.]+)`")
    broken = []
    for info in pkgutil.walk_packages(workbench.__path__, "workbench."):
        if info.name.endswith("__main__"):
            continue
        source = inspect.getsource(importlib.import_module(info.name))
        broken += [(info.name, ref) for ref in role.findall(source) if not _resolves(ref)]
    assert not broken


# -- 13. every parameter documented where a function has a Parameters section -------------------


def _parameters_section(doc: str) -> str | None:
    found = re.search(r"^Parameters\n-+\n(.*?)(?=^\S[^\n]*\n-+\n|\Z)", doc, re.S | re.M)
    return found.group(1) if found else None


@pytest.mark.parametrize("package", ["workbench.continuation", "workbench.analysis"])
def test_every_parameter_is_documented_where_there_is_a_parameters_section(package):
    module = importlib.import_module(package)
    missing, checked = [], 0
    for name in module.__all__:
        fn = getattr(module, name)
        if not inspect.isfunction(fn):
            continue
        section = _parameters_section(inspect.getdoc(fn) or "")
        if section is None:
            continue
        checked += 1
        for p in inspect.signature(fn).parameters:
            if not re.search(rf"(?<![\w.]){re.escape(p)}\b", section):
                missing.append(f"{name}({p})")
    assert checked >= 5 and not missing


def test_named_functions_and_scene_fields_are_documented():
    from workbench.analysis import floquet, floquet_sweep
    from workbench.continuation import chaos_map
    from workbench.scene import Scene

    for fn, names in (
        (floquet, ["max_iterations"]),
        (floquet_sweep, ["rtol"]),
        (chaos_map, ["client", "workers", "chunk", "restart", "progress"]),
    ):
        section = _parameters_section(inspect.getdoc(fn))
        assert all(re.search(rf"^{n}\b", section, re.M) for n in names), fn.__name__
    doc = inspect.getdoc(Scene)
    assert re.search(r"^title : str$", doc, re.M) and re.search(r"^description : str$", doc, re.M)
