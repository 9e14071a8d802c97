"""`make demo` (issue 40 item 9): it installs the runtime package only, runs studies/demo.toml,
the default scene run long enough and recorded finely enough for what its figures claim, and
draws them without a warning: a Poincaré section with at least the points its own title asks
for, phase portraits whose records resolve the impacts."""

import os
import re
import shutil
import stat
import subprocess
import tomllib
from pathlib import Path

import pytest

import workbench
from workbench.plot._phase import _FEW_PERIODS, run_poincare_figure

ROOT = Path(__file__).resolve().parents[2]
DEMO = ROOT / "studies" / "demo.toml"
DEFAULT = ROOT / "studies" / "ninebar.toml"


def test_the_demo_is_the_default_scene_run_longer_and_recorded_finer():
    """The demo's scene is studies/ninebar.toml but for its title, [run] and [record]."""
    demo, default = (tomllib.loads(p.read_text()) for p in (DEMO, DEFAULT))
    differ = {k for k in demo.keys() | default.keys() if demo.get(k) != default.get(k)}
    assert differ == {"title", "run", "record"}
    assert demo["title"].startswith(default["title"] + ": ")
    assert demo["run"]["transient_cycles"] == default["run"]["transient_cycles"]
    assert demo["record"]["samples_per_period"] > default["record"]["samples_per_period"]


def test_the_demo_section_has_the_points_its_figure_asks_for():
    """One stroboscopic point per recorded cycle and its ends: cycles + 1 >= the figure's
    threshold (below it, its title says the section shows no structure yet)."""
    scene = workbench.load_scene(DEMO)
    assert scene.run["cycles"] + 1 >= _FEW_PERIODS
    cycles, spp = re.search(r": (\d+) cycles, ([\d ]+) records per cycle$", scene.title).groups()
    assert (int(cycles), int(spp.replace(" ", ""))) == (
        scene.run["cycles"],
        scene.record["samples_per_period"],
    )


def _fake_python(path: Path, log: Path) -> Path:
    """A stand-in for python3: ``-m venv DIR`` makes DIR/bin/python and DIR/bin/workbench (the
    same stand-in); every call appends its arguments to ``log``."""
    path.write_text(
        "#!/bin/sh\n"
        f'echo "$(basename "$0") $*" >> "{log}"\n'
        'if [ "$1 $2" = "-m venv" ]; then\n'
        '  mkdir -p "$3/bin" && cp "$0" "$3/bin/python" && cp "$0" "$3/bin/workbench"\n'
        "fi\n"
    )
    path.chmod(path.stat().st_mode | stat.S_IXUSR)
    return path


def _make(tmp_path: Path, target: str) -> list[str]:
    """Run ``make TARGET`` of the repository's Makefile with .venv in ``tmp_path`` and python3
    replaced by :func:`_fake_python`; the calls it made (program and arguments), in order."""
    log = tmp_path / "calls.log"
    python = _fake_python(tmp_path / "python3", log)
    venv = tmp_path / "venv"
    target = target.replace(".venv", str(venv))
    before = log.read_text().splitlines() if log.exists() else []
    subprocess.run(
        ["make", "-s", "-f", str(ROOT / "Makefile"), f"VENV={venv}", f"PYTHON={python}",
         f"OUT={tmp_path / 'out'}", target],
        cwd=ROOT, check=True, capture_output=True, text=True, env={**os.environ, "MAKEFLAGS": ""},
    )  # fmt: skip
    return log.read_text().splitlines()[len(before) :]


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
@pytest.mark.parametrize("first", ["demo", "test"])
def test_make_demo_installs_the_runtime_only_and_the_extras_go_on_top(tmp_path, first):
    """`make demo` installs the package without extras; the test target's install adds the
    extras on top, in either order, and neither installs again once done."""
    runtime = "python -m pip install --quiet -e ."
    extras = runtime + "[test,verify,docs]"
    demo_run = "workbench run studies/demo.toml -o"
    steps = ["demo", ".venv/.installed"] if first == "demo" else [".venv/.installed", "demo"]
    calls = [_make(tmp_path, step) for step in steps]
    made = [c for c in calls[0] if "-m venv" in c]
    assert len(made) == 1
    if first == "demo":
        installs = [c for c in calls[0] if "pip install" in c and "--upgrade pip" not in c]
        assert installs == [runtime]
        assert any(c.startswith(demo_run) for c in calls[0])
        assert [c for c in calls[1] if "pip install" in c] == [extras]
    else:
        assert [c for c in calls[0] if "pip install" in c and "--upgrade" not in c] == [extras]
        assert not [c for c in calls[1] if "pip" in c or "venv" in c]
        assert any(c.startswith(demo_run) for c in calls[1])
    again = _make(tmp_path, "demo") + _make(tmp_path, ".venv/.installed")
    assert not [c for c in again if "pip" in c or "venv" in c]


@pytest.mark.slow
def test_the_demo_runs_without_a_warning_and_its_section_shows_its_points(tmp_path, capsys):
    """What `make demo` runs, in process: no warning (none about coarse records), and the
    Poincaré section's title counts the points without saying they are too few."""
    from workbench.cli import main

    out = tmp_path / "ninebar.nc"
    code = main(["run", str(DEMO), "-o", str(out), "--figures", str(tmp_path / "figures"), "-q"])
    err = capsys.readouterr().err
    assert code == 0 and "warning" not in err.lower(), err
    assert sorted(p.name for p in (tmp_path / "figures").glob("*.png")) == [
        "ninebar_overview.png",
        "ninebar_phase.png",
        "ninebar_poincare.png",
        "ninebar_timeseries.png",
    ]
    fig = run_poincare_figure(workbench.open_run(out))
    title = fig.get_suptitle()
    points = int(re.search(r"\((\d+) periods, one point each\)", title).group(1))
    assert points >= _FEW_PERIODS and "fewer than" not in title
