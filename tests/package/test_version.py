"""One version, said everywhere, and a format version on every archive (issue 26 item 1):
pyproject.toml, ``workbench.__version__``, ``workbench --version``, the archives' ``source`` and
``format_version``; an archive of the older format (workbench 0.1.0) is upgraded or refused
with a message that says what to do; a newer one is refused. One distribution name (issue 40
item 1): pyproject's, the installed metadata's and every install command's."""

import re
import shlex
import tomllib
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import workbench
from workbench.archive import ArchiveError
from workbench.cli import main

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = Path(__file__).parents[1] / "fixtures"
#: the distribution's name (the project called ``workbench`` on PyPI is another one); the
#: package one imports and the command stay ``workbench``
DISTRIBUTION = "clearance-workbench"
#: where install commands are shown to users: the README, the docs' pages, the notebooks and
#: the package's own messages
INSTALL_SOURCES = [
    ROOT / "README.md",
    *sorted(p for p in (ROOT / "docs").rglob("*.md") if not p.is_symlink()),
    *sorted((ROOT / "notebooks").glob("*.ipynb")),
    *sorted((ROOT / "workbench").rglob("*.py")),
]
#: a requirement (a name with extras) or a path (``.``, ``.[extras]``) that pip installs
_TARGET = re.compile(r"(?P<name>\.|[A-Za-z0-9][A-Za-z0-9._-]*)(?:\[(?P<extras>[\w,-]+)\])?")


def test_one_version():
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert pyproject["project"]["version"] == workbench.__version__
    assert re.fullmatch(r"\d+\.\d+\.\d+", workbench.__version__)
    changelog = (ROOT / "CHANGELOG.md").read_text()
    assert f"## {workbench.__version__}" in changelog  # every version says what it changed
    assert f"format {workbench.FORMAT_VERSION}" in changelog


def test_cli_version(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out.strip()
    assert out == f"workbench {workbench.__version__} (archive format {workbench.FORMAT_VERSION})"


def test_every_archive_carries_the_format(tmp_path):
    ds = workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 2}})
    assert ds.attrs["format_version"] == workbench.FORMAT_VERSION
    assert ds.attrs["source"].startswith(f"workbench {workbench.__version__} ")
    path = workbench.save_run(ds, tmp_path / "run.nc")
    assert workbench.open_run(path).identical(ds)
    # a Dataset that workbench did not build (a figure's data, a summary) is stamped on write
    other = xr.Dataset({"y": ("x", np.arange(3.0), {"units": "m"})})
    back = workbench.open_run(workbench.save_run(other, tmp_path / "other.nc"))
    assert back.attrs["format_version"] == workbench.FORMAT_VERSION
    assert "format_version" not in other.attrs  # the caller's Dataset is left alone
    classic = workbench.open_run(workbench.save_run(other, tmp_path / "c.nc", classic=True))
    assert classic.attrs["format_version"] == workbench.FORMAT_VERSION


def test_a_format1_run_is_upgraded():
    """data/chaos_run.nc as workbench 0.1.0 wrote it (first 200 records): run_status 'done'."""
    raw = xr.open_dataset(FIXTURES / "format1_run.nc")
    assert "format_version" not in raw.attrs and raw.attrs["run_status"] == "done"
    ds = workbench.open_run(FIXTURES / "format1_run.nc")
    assert workbench.Status.from_label(ds.attrs["run_status"]) is workbench.Status.OK
    assert ds.attrs["format_version"] == workbench.FORMAT_VERSION
    assert ds.attrs["upgraded_from_format"] == 1
    xr.testing.assert_identical(ds.clearance_x, raw.clearance_x.load())


def test_a_format2_run_is_read_as_it_was_written(tmp_path):
    """Format 2 (workbench 0.2.0 to 0.5.1) stored the simulated time in "s" with xarray's
    encoding; format 3 stores it as a CF time coordinate (workbench.archive._format). A format-2
    file reads back as the same dataset, upgraded."""
    ds = workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 2}})
    old = ds.copy()
    old.attrs["format_version"] = np.int32(2)
    old.to_netcdf(tmp_path / "format2.nc")  # xarray's writer: what save_run wrote in format 2
    with xr.open_dataset(tmp_path / "format2.nc") as raw:
        assert raw.time.attrs["units"] == "s" and raw.time.dtype == np.float64
    back = workbench.open_run(tmp_path / "format2.nc")
    assert back.attrs.pop("upgraded_from_format") == 2
    assert back.identical(ds)


def test_a_format1_campaign_is_upgraded_to_todays_flags(tmp_path):
    """data/bifurcation_speed.nc as workbench 0.1.0 wrote it (4 points): flags 'ok
    solver_failed terminated_early invalid_parameters'. The upgraded flags are those a
    campaign writes today, and each point keeps its meaning."""
    from workbench.campaign._block import STATUS_ATTRS

    ds = workbench.open_run(FIXTURES / "format1_campaign.nc")
    assert ds.status.attrs["flag_meanings"] == STATUS_ATTRS["flag_meanings"]
    np.testing.assert_array_equal(ds.status.attrs["flag_values"], STATUS_ATTRS["flag_values"])
    assert (ds.status.values == 0).all()
    # terminated_early -> terminated, invalid_parameters -> invalid_parameters, at other codes
    raw = xr.open_dataset(FIXTURES / "format1_campaign.nc").load()
    raw["status"].values[:] = [0, 2, 3, 0]
    raw.to_netcdf(tmp_path / "old.nc")
    up = workbench.open_run(tmp_path / "old.nc")
    attrs = up.status.attrs
    meanings = dict(zip(attrs["flag_values"], attrs["flag_meanings"].split(), strict=True))
    assert [meanings[v] for v in up.status.values] == [
        "ok",
        "terminated",
        "invalid_parameters",
        "ok",
    ]
    # solver_failed has no single counterpart: refused, saying what to do
    raw["status"].values[:] = [0, 1, 1, 0]
    raw.to_netcdf(tmp_path / "failed.nc")
    with pytest.raises(ArchiveError, match=r"format 1\).* 2 of its 'status' flags.*--restart"):
        workbench.open_run(tmp_path / "failed.nc")


def test_a_newer_format_is_refused_and_a_foreign_file_left_alone(tmp_path):
    ds = xr.Dataset({"y": ("x", np.arange(3.0))})
    ds.attrs["format_version"] = np.int32(workbench.FORMAT_VERSION + 1)
    ds.to_netcdf(tmp_path / "new.nc")
    with pytest.raises(ArchiveError, match="newer than this workbench .* upgrade workbench"):
        workbench.open_run(tmp_path / "new.nc")
    foreign = xr.Dataset({"y": ("x", np.arange(3.0))}, attrs={"source": "another tool"})
    foreign.to_netcdf(tmp_path / "foreign.nc")
    assert "format_version" not in workbench.open_run(tmp_path / "foreign.nc").attrs


def test_the_changelog_has_each_version_once_newest_first():
    changelog = (ROOT / "CHANGELOG.md").read_text()
    versions = re.findall(r"^## (\d+)\.(\d+)\.(\d+)", changelog, re.M)
    as_numbers = [tuple(map(int, v)) for v in versions]
    assert as_numbers == sorted(set(as_numbers), reverse=True), versions
    assert ".".join(versions[0]) == workbench.__version__


def _install_targets(text: str) -> list[tuple[str, set[str]]]:
    """What each ``pip install ...`` of ``text`` installs: (name or ".", extras), its options
    skipped, up to the first word that is neither (the end of the command in prose)."""
    found = []
    for command in re.findall(r"pip install ([^`\n\"]+)", text):
        for word in shlex.split(command.replace("\\", " "), comments=True):
            if word.startswith("-"):
                continue
            target = _TARGET.fullmatch(word)
            if target is None:
                break
            extras = target.group("extras")
            found.append((target.group("name"), set(extras.split(",")) if extras else set()))
    return found


def test_install_commands_name_the_distribution():
    """No command installs the PyPI project called ``workbench`` (which is not this one): each
    names ``clearance-workbench`` or a checkout (``.``), with extras that pyproject defines."""
    extras = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"])  # fmt: skip
    seen = []
    for source in INSTALL_SOURCES:
        for name, wanted in _install_targets(source.read_text()):
            where = f"{source.relative_to(ROOT)}: pip install {name}"
            assert name.lower().replace("_", "-") != "workbench", where
            if name in (".", DISTRIBUTION):
                assert wanted <= extras, (where, wanted - extras)
                seen.append(name)
    assert DISTRIBUTION in seen and "." in seen  # the test reads the commands it checks


def test_the_check_of_install_commands_can_fail():
    assert _install_targets("run `pip install -e '.[verify]'` (exudyn)") == [(".", {"verify"})]
    text = "needs dask-jobqueue: pip install 'workbench[cluster]' (or dask-jobqueue)"
    assert _install_targets(text) == [("workbench", {"cluster"})]


def test_the_distribution_name_and_its_installed_metadata():
    """pyproject names the distribution; the installed package reports that name, this
    version and the ``workbench`` command (skipped where workbench runs from a source tree
    that no distribution installed)."""
    from importlib.metadata import distribution, packages_distributions

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["name"] == DISTRIBUTION
    assert project["scripts"] == {"workbench": "workbench.cli:main"}
    # (a distribution seen twice, from site-packages and from an egg-info in the checkout)
    providers = sorted(set(packages_distributions().get("workbench", [])))
    if not providers:
        pytest.skip("no installed distribution provides the package workbench")
    assert providers == [DISTRIBUTION], (
        f"the package workbench is installed by {providers}: pip uninstall the others, then "
        "pip install -e . (make test does it when pyproject.toml changes)"
    )
    dist = distribution(DISTRIBUTION)
    assert dist.metadata["Name"] == DISTRIBUTION
    assert dist.version == workbench.__version__, "a stale install: pip install -e ."
    scripts = {ep.name: ep.value for ep in dist.entry_points if ep.group == "console_scripts"}
    assert scripts == {"workbench": "workbench.cli:main"}
