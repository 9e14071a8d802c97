"""What a person meets first on the command line (issue 40, item 10): a help that starts at
once, a reference page written from the parsers, refusals that name the wrong value first, and
figures whose place is said."""

import subprocess
import sys
from pathlib import Path

import pytest

import workbench
from workbench.cli import main
from workbench.cli._reference import PAGE, reference_page

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("numba", "xarray", "dask", "matplotlib", "scipy", "pandas", "distributed", "netCDF4")


def test_help_imports_no_numerical_library():
    """``workbench --help`` and every ``workbench COMMAND --help`` parse with none of numba,
    xarray, dask, matplotlib (nor scipy, pandas) imported: counted in a fresh process, not
    timed."""
    code = (
        "import sys\n"
        "from workbench.cli import build_parser, main\n"
        "commands = [None] + list(next(a for a in build_parser()._actions"
        " if a.dest == 'command').choices)\n"
        "for command in commands:\n"
        "    try:\n"
        "        main(['--help'] if command is None else [command, '--help'])\n"
        "    except SystemExit:\n"
        "        pass\n"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules), file=sys.stderr)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert out.stderr.strip().splitlines()[-1] == "[]", out.stderr[-2000:]
    assert "usage: workbench verify" in out.stdout and "usage: workbench [-h]" in out.stdout


def test_import_workbench_loads_its_names_on_first_use():
    """The public names still come with ``import workbench`` (loaded when first used)."""
    code = (
        "import sys, workbench\n"
        "before = 'numba' in sys.modules\n"
        "from workbench import simulate, Status\n"
        "print(before, 'numba' in sys.modules, simulate.__module__, Status.OK.label)\n"
        "print(workbench.campaign.summary.__module__, workbench.continuation.__name__)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert out.stdout.split() == [
        "False",
        "True",
        "workbench.run._simulate",
        "ok",
        "workbench.campaign._assemble",
        "workbench.continuation",
    ]
    assert sorted(set(workbench.__all__) - set(dir(workbench))) == []
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        workbench.nope  # noqa: B018


def test_the_reference_page_is_what_the_parsers_say_now():
    page = ROOT / PAGE
    assert page.read_text() == reference_page(), (
        f"{PAGE} differs from the parsers: run `python -m workbench.cli._reference`"
    )
    assert "cli.md" in (ROOT / "mkdocs.yml").read_text()


def test_the_reference_page_lists_every_command_and_option():
    from workbench.cli import build_parser

    text = reference_page()
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for name, parser in sub.choices.items():
        assert f"\n## {name}\n" in text and f"usage: workbench {name}" in text
        for action in parser._actions:
            for option in action.option_strings:
                if option not in ("-h", "--help") and action.help != "==SUPPRESS==":
                    assert f"`{option}" in text, (name, option)


def _scene(tmp_path: Path) -> str:
    path = tmp_path / "duffing.toml"
    path.write_text('[model]\nname = "duffing"\n[parameters]\ngamma = 0.25\n')
    return str(path)


def test_orbit_names_an_unknown_parameter_before_anything_else(tmp_path, capsys):
    """``--param nope`` without --stop: the refusal names the parameter and the allowed ones
    (not the missing --stop of a parameter that does not exist)."""
    code = main(["orbit", _scene(tmp_path), "-o", str(tmp_path / "b.nc"), "--param", "nope"])
    err = capsys.readouterr().err
    assert code == 2
    assert err == (
        "workbench orbit: error: --param 'nope': not a parameter of model 'duffing'; allowed: "
        "alpha, beta, delta, gamma, omega, v0, x0\n"
    )


def test_analyse_without_output_says_where_its_figures_went(tmp_path, monkeypatch, capsys):
    run = tmp_path / "run.nc"
    scene = {"model": {"name": "lorenz"}, "run": {"duration": 20.0, "transient": 5.0}}
    workbench.save_run(workbench.simulate(scene), run)
    here = tmp_path / "here"
    here.mkdir()
    monkeypatch.chdir(here)
    assert main(["analyse", str(run), "--var", "x", "--surrogates", "0"]) == 0
    out = capsys.readouterr().out.splitlines()
    written = sorted(p.name for p in here.iterdir())
    assert written and all(name.endswith(".png") for name in written)
    assert out[-1] == (f"figures written to the current directory, {here} (-o DIR for another)")
    assert main(["analyse", str(run), "--var", "x", "--surrogates", "0", "-o", str(tmp_path)]) == 0
    assert "current directory" not in capsys.readouterr().out
