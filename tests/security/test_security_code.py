"""No code from data (issue 37, finding 3): a ``[model] module`` is imported only for a scene the
user gives directly (a scene file, a mapping, a Scene) or a module the user trusts by name
(``trust_modules=``, ``--trust-module``). A scene read out of an archive or a campaign's manifest
that names another module is refused in one line that names the module and the way to trust it;
a scene refused for any other reason imports nothing; a module is loaded from the import path or
by file path beside the scene, never by putting the scene's folder in front of the installed
libraries; a malformed name is one line.

Every planted module writes a marker file when imported: the marker must not appear.
"""

import itertools
import os
import subprocess
import sys
import uuid
from pathlib import Path

import pytest

import workbench
from workbench import SceneError
from workbench.campaign import CampaignError, Store, expand_sweep, task_scene

CLI = [sys.executable, "-m", "workbench.cli"]
DUFFING = {"model": {"name": "duffing"}, "run": {"cycles": 2}, "record": {"samples_per_period": 4}}
_names = itertools.count()


def planted(directory: Path) -> tuple[str, Path]:
    """A module (a name of its own, so never imported before) in ``directory`` that writes a
    marker file when imported; returns its name and the marker's path."""
    name = f"planted_{uuid.uuid4().hex[:8]}_{next(_names)}"
    marker = directory / f"{name}.imported"
    (directory / f"{name}.py").write_text(
        f"import pathlib\npathlib.Path({str(marker)!r}).write_text('imported')\n"
    )
    return name, marker


def with_module(toml: str, module: str) -> str:
    """Scene TOML with ``[model] module = module`` added (as a hostile file would have it)."""
    head = '[model]\nname = "duffing"\n'
    assert head in toml
    return toml.replace(head, f'{head}module = "{module}"\n')


@pytest.fixture
def importable(tmp_path, monkeypatch):
    """A planted module on ``sys.path`` (importable by name, as the old code would have it)."""
    directory = tmp_path / "importable"
    directory.mkdir()
    monkeypatch.syspath_prepend(str(directory))
    name, marker = planted(directory)
    return name, marker


@pytest.fixture(scope="module")
def stored_run(tmp_path_factory) -> Path:
    """A short Duffing run whose stored scene names a module (as a hostile archive would)."""
    path = tmp_path_factory.mktemp("archive") / "run.nc"
    spec = DUFFING | {"run": {"cycles": 200, "transient_cycles": 20}}
    ds = workbench.simulate(spec | {"record": {"samples_per_period": 20}})
    workbench.save_run(ds, path)
    return path


def hostile_copy(stored_run: Path, directory: Path, module: str) -> Path:
    ds = workbench.open_run(stored_run).load()
    ds.attrs["scene"] = with_module(ds.attrs["scene"], module)
    path = directory / "hostile.nc"
    workbench.save_run(ds, path)
    return path


# -- stored text -----------------------------------------------------------------------------
def test_stored_scene_text_naming_a_module_is_refused_before_any_import(importable):
    name, marker = importable
    text = with_module(workbench.load_scene(DUFFING).to_toml(), name)
    with pytest.raises(SceneError) as err:
        workbench.scene_from_toml(text)
    message = str(err.value)
    assert message.startswith(f"model.module: the scene text names the module '{name}'")
    assert f"trust_modules=('{name}',)" in message and f"--trust-module {name}" in message
    assert "\n" not in message
    assert not marker.exists() and name not in sys.modules


def test_trust_modules_imports_the_named_module_and_only_that(importable):
    name, marker = importable
    text = with_module(workbench.load_scene(DUFFING).to_toml(), name)
    with pytest.raises(SceneError, match="names the module"):
        workbench.scene_from_toml(text, trust_modules=("some_other_module",))
    assert not marker.exists()
    scene = workbench.scene_from_toml(text, trust_modules=name)  # one name: a str will do
    assert marker.exists() and scene.model_module == name
    # imported on the user's word: the same text now loads without naming it again
    assert workbench.scene_from_toml(text) == scene


def test_an_archive_scene_naming_a_module_is_refused_by_the_analysis(
    stored_run, importable, tmp_path
):
    """``open_run`` + an analysis that rebuilds the stored scene (jacobian_spectrum of a run)."""
    name, marker = importable
    run = workbench.open_run(hostile_copy(stored_run, tmp_path, name))
    with pytest.raises(SceneError, match=f"names the module '{name}'"):
        workbench.analysis.jacobian_spectrum(run)
    assert not marker.exists() and name not in sys.modules


def test_analyse_equations_refuses_the_stored_module_in_one_line(stored_run, tmp_path):
    """``workbench analyse --equations`` in a fresh process started where the planted module
    lies (``python -m`` puts the working directory on its path): refused before any work, in
    one line naming the module and --trust-module; with --trust-module it is imported."""
    name, marker = planted(tmp_path)
    archive = hostile_copy(stored_run, tmp_path, name)
    argv = ["analyse", str(archive), "--var", "x", "--equations", "--surrogates", "0"]
    out = subprocess.run(
        [*CLI, *argv, "-o", "figs"], cwd=tmp_path, capture_output=True, text=True, timeout=600
    )
    assert out.returncode == 2, out.stderr
    assert out.stderr.startswith(
        f"workbench analyse: error: model.module: the scene text names the module '{name}'"
    )
    assert f"--trust-module {name}" in out.stderr and out.stderr.count("\n") == 1
    assert out.stdout == ""  # refused before the analysis
    assert not marker.exists()
    out = subprocess.run(
        [*CLI, *argv, "-o", "figs", "--trust-module", name],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert marker.exists() and "LLE from the equations (Benettin)" in out.stdout


def test_a_resumed_manifest_naming_a_module_is_refused_before_any_import(importable, tmp_path):
    """The manifest's scene is data: a module it names that the given scene does not is the
    difference, named in one line; nothing is imported (before: imported, then refused)."""
    name, marker = importable
    scene = workbench.load_scene(DUFFING | {"sweep": {"gamma": [0.3, 0.4]}})
    st = Store(tmp_path / "c.nc")
    manifest = st.write_manifest(scene, expand_sweep(scene), 1, "cid", [(0,), (1,)])
    manifest["scene"] = with_module(manifest["scene"], name)
    st.save_manifest(manifest)
    with pytest.raises(CampaignError) as err:
        workbench.run_campaign(scene, tmp_path / "c.nc", workers=1)
    assert not marker.exists() and name not in sys.modules
    message = str(err.value)
    assert f"names the model module '{name}' (given: none)" in message and "\n" not in message
    assert f"model.module = '{name}'" in message and "restart=True" in message


# -- validate first, import after ------------------------------------------------------------
@pytest.mark.parametrize(
    "extra, key",
    [
        ({"solver": {"method": "bogus"}}, "solver.method"),
        ({"solver": {"rtol": -1.0}}, "solver.rtol"),
        ({"bogus": {}}, "bogus"),
        ({"run": 3}, "run"),
        ({"title": 3}, "title"),
        ({"model": {"name": "duffing", "bogus": 1}}, "model.bogus"),
        ({"model": {}}, "model.name"),
    ],
)
def test_a_scene_refused_for_another_reason_imports_nothing(importable, extra, key):
    name, marker = importable
    spec = {"model": {"name": "duffing"}} | extra
    spec["model"] = dict(spec["model"], module=name)
    with pytest.raises(SceneError) as err:
        workbench.load_scene(spec)
    assert err.value.key == key
    assert not marker.exists() and name not in sys.modules


@pytest.mark.parametrize("value", ["..x", "a..b", "1x", "x-y", "", " ", "x.", ".x", "class", 3])
@pytest.mark.parametrize("how", ["load_scene", "scene_from_toml"])
def test_a_malformed_module_name_is_one_line(value, how):
    spec = {"model": {"name": "duffing", "module": value}}
    with pytest.raises(SceneError) as err:
        if how == "load_scene":
            workbench.load_scene(spec)
        else:
            import tomli_w

            workbench.scene_from_toml(tomli_w.dumps(spec), trust_modules=(str(value),))
    assert str(err.value) == (
        "model.module: must be a module name: Python identifiers joined by dots (e.g. "
        f"'rossler_model' or 'mypackage.models'), got {value!r}"
    )


# -- where a trusted module comes from -------------------------------------------------------
def shared_scene(directory: Path, spec: dict) -> tuple[str, Path, Path]:
    """A scene folder as a colleague might share it: the scene, the module it names (which
    appends the pid of each process that imports it to ``<name>.pids``) and a ``netCDF4.py``
    that writes a marker if anyone imports it instead of the installed library."""
    directory.mkdir()
    name = f"helper_{uuid.uuid4().hex[:8]}"
    pids = directory / f"{name}.pids"
    (directory / f"{name}.py").write_text(
        "import os, pathlib\n"
        f"with pathlib.Path({str(pids)!r}).open('a') as f:\n"
        "    f.write(f'{os.getpid()}\\n')\n"
    )
    marker = directory / "netCDF4.imported"
    (directory / "netCDF4.py").write_text(
        f"import pathlib\npathlib.Path({str(marker)!r}).write_text('shadowed')\n"
        "raise ImportError('a netCDF4.py beside the scene was imported')\n"
    )
    scene = with_module(workbench.load_scene(spec).to_toml(), name)
    (directory / "scene.toml").write_text(scene)
    return name, pids, marker


def test_a_netcdf4_py_beside_a_shared_scene_does_not_replace_the_library(tmp_path):
    """``workbench run`` of a scene whose module lies beside it: the module is loaded by its
    file path, the folder is not put on sys.path, so the netCDF4.py lying there is not what
    the archive is written with (before: the run ended in its ImportError)."""
    name, pids, marker = shared_scene(tmp_path / "shared", DUFFING)
    out = subprocess.run(
        [*CLI, "run", str(tmp_path / "shared" / "scene.toml"), "-o", "r.nc", "-q"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert out.returncode == 0, out.stderr
    assert not marker.exists()
    assert len(pids.read_text().split()) == 1  # the module beside the scene: imported once
    assert f'module = "{name}"' in workbench.open_run(tmp_path / "r.nc").attrs["scene"]


CONTINUED = {"omega": [1.1, 1.11, 1.12], "continuation": {"direction": "down", "segments": 2}}


@pytest.mark.parametrize("context", ["", "spawn"], ids=["fork_server", "spawn"])
@pytest.mark.parametrize(
    "sweep", [{"gamma": [0.3, 0.35, 0.4, 0.45]}, CONTINUED], ids=["blocks", "continued"]
)
def test_campaign_workers_load_the_module_by_file_path_not_from_sys_path(tmp_path, sweep, context):
    """``workbench campaign`` (blocks of points, and a continued sweep's segments): the client
    and its worker processes import the module beside the scene (the workers by the file path
    the client found it at: it is not on their path); none imports the netCDF4.py there. The
    local pool's fork server imports it once for its workers; spawned workers (dask's
    ``multiprocessing.context``: no preloading server) import it from their tasks."""
    name, pids, marker = shared_scene(tmp_path / "shared", DUFFING | {"sweep": sweep})
    out = subprocess.run(
        [*CLI, "campaign", str(tmp_path / "shared" / "scene.toml"), "-o", "c.nc", "--workers", "2"]
        + ["-q"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=900,
        env=os.environ | ({"DASK_MULTIPROCESSING__CONTEXT": context} if context else {}),
    )
    assert out.returncode == 0, out.stderr
    assert not marker.exists()
    importers = set(pids.read_text().split())
    # the client, and the fork server (its workers inherit the module) or the spawned workers
    assert len(importers) >= 2
    ds = workbench.open_run(tmp_path / "c.nc")
    assert (ds.status.values == 0).all() and ds.status.size == len(sweep.get("gamma", [0] * 3))


def test_a_task_scene_imports_its_module_by_file_path(tmp_path):
    """What a worker does with a task (``task_scene``): the module the client named, from the
    directory the client found it in, without putting that directory on sys.path."""
    name, marker = planted(tmp_path)
    path_before = list(sys.path)
    text = with_module(workbench.load_scene(DUFFING).to_toml(), name)
    scene = task_scene(text, name, str(tmp_path))
    assert scene.model_module == name and marker.exists()
    assert sys.path == path_before
    assert Path(sys.modules[name].__file__) == tmp_path / f"{name}.py"


def test_a_scene_file_loads_its_module_by_file_path_and_trusts_it(tmp_path, monkeypatch):
    """The documented workflow: a scene file whose module lies beside it (not on the path, not
    in the working directory) loads, without changing sys.path; the same scene's stored text
    then loads in this process (the module was imported on the user's word)."""
    directory = tmp_path / "scenes"
    directory.mkdir()
    name, marker = planted(directory)
    (directory / "s.toml").write_text(with_module(workbench.load_scene(DUFFING).to_toml(), name))
    monkeypatch.chdir(tmp_path)
    path_before = list(sys.path)
    scene = workbench.load_scene(directory / "s.toml")
    assert marker.exists() and scene.model_module == name and sys.path == path_before
    assert workbench.scene_from_toml(scene.to_toml()) == scene


def test_the_import_path_comes_before_the_scene_folder(tmp_path, importable):
    """A module of that name on the import path is the one imported: a file of the same name
    beside the scene is not loaded."""
    name, marker = importable
    directory = tmp_path / "scenes"
    directory.mkdir()
    beside = directory / "beside.imported"
    (directory / f"{name}.py").write_text(
        f"import pathlib\npathlib.Path({str(beside)!r}).write_text('imported')\n"
    )
    (directory / "s.toml").write_text(with_module(workbench.load_scene(DUFFING).to_toml(), name))
    workbench.load_scene(directory / "s.toml")
    assert marker.exists() and not beside.exists()


def test_a_missing_module_is_one_line(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SceneError) as err:
        workbench.load_scene({"model": {"name": "duffing", "module": "no_such_module_xyz"}})
    assert str(err.value) == (
        "model.module: cannot import 'no_such_module_xyz': put no_such_module_xyz.py beside "
        "the scene file or in the working directory, or on PYTHONPATH"
    )


def test_a_scene_error_crosses_processes_intact():
    """A worker's SceneError (e.g. the module it is told to import is gone) reaches the client
    as the same one-line error; before, unpickling it raised a TypeError that broke the pool
    ("a worker process of the local pool died")."""
    import pickle

    for err in (SceneError("model.module", "cannot import 'x'"), SceneError("", "no key")):
        back = pickle.loads(pickle.dumps(err))
        assert type(back) is SceneError and back.key == err.key and str(back) == str(err)
