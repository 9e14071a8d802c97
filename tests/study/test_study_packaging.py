"""The paper's studies ship with the package: an installed wheel lists and loads them, and the
repository's ``studies/`` stays the one place they are edited (``workbench/study/scenes`` links
to it)."""

import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

from workbench.study import available_studies, load_study, report_path
from workbench.study._spec import REPOSITORY_STUDIES, STUDIES_DIR

ROOT = Path(__file__).resolve().parents[2]


def _scene_files(root: Path) -> set[str]:
    return {str(p.relative_to(root)) for p in root.rglob("*.toml")}


def test_the_package_scenes_are_the_repository_studies():
    assert STUDIES_DIR.resolve() == REPOSITORY_STUDIES.resolve() == (ROOT / "studies").resolve()
    assert report_path("out/studies") == ROOT / "studies" / "REPORT.md"
    assert "chaos" in available_studies() and len(available_studies()) >= 10


def test_the_package_data_patterns_cover_every_scene():
    """Every TOML under studies/ matches a package-data pattern of pyproject.toml (so the
    wheel has it): a scene in a deeper directory would need a new pattern."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    patterns = config["tool"]["setuptools"]["package-data"]["workbench.study"]
    base = ROOT / "workbench" / "study"
    packaged = {
        str(p.resolve().relative_to((ROOT / "studies").resolve()))
        for pattern in patterns
        for p in base.glob(pattern)
    }
    assert packaged == _scene_files(ROOT / "studies")


def _copy_of_the_repository(dest: Path) -> Path:
    skip = shutil.ignore_patterns(
        ".venv", ".git", "out", "build", "dist", "*.egg-info", "__pycache__", ".*_cache", "*.nc"
    )
    shutil.copytree(ROOT, dest, symlinks=True, ignore=skip)
    return dest


@pytest.mark.slow
def test_an_installed_wheel_lists_and_loads_the_studies(tmp_path):
    """Build the wheel (pip, from a copy of the working tree), unpack it, and run the command
    line from it outside the repository: ``study list`` prints every study, a study loads, an
    unknown one is one line, and the report would go beside the summaries."""
    src = _copy_of_the_repository(tmp_path / "src")
    build = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(tmp_path), str(src)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert build.returncode == 0, build.stderr[-2000:]
    (wheel,) = tmp_path.glob("clearance_workbench-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    expected = {f"workbench/study/scenes/{f}" for f in _scene_files(ROOT / "studies")}
    assert expected <= set(names), sorted(expected - set(names))[:5]
    assert "workbench/campaign/compile_times.json" in names  # the compile notice's record
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)
    run = tmp_path / "elsewhere"
    run.mkdir()
    env = dict(os.environ, PYTHONPATH=str(site))

    def cli(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "workbench.cli", *args],
            cwd=run,
            env=env,
            capture_output=True,
            text=True,
            timeout=300,
        )

    listed = cli("study", "list")
    assert listed.returncode == 0, listed.stderr
    assert listed.stdout.split() == available_studies()
    code = (
        "import workbench.study as s\n"
        f"assert s.__file__.startswith({str(site)!r}), s.__file__\n"
        "study = s.load_study('chaos')\n"
        "print(len(study.cases), s.report_path('out'))\n"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", code], cwd=run, env=env, capture_output=True, text=True
    )
    assert loaded.returncode == 0, loaded.stderr
    cases, report = loaded.stdout.split()
    assert int(cases) == len(load_study("chaos").cases) and report == "out/REPORT.md"
    unknown = cli("study", "no_such_study", "-q")
    assert unknown.returncode == 2
    assert unknown.stderr.strip().startswith("workbench study: error: no study 'no_such_study'")
    assert "Traceback" not in unknown.stderr
