"""The kernel cache loads only what this user compiled (issue 37, finding 2): a pickle planted in
numba's index or data file of a workbench function does not run (the function is compiled
again, with one notice); a cache root that is not the user's alone is refused in one line; a
package, a module or bytecode planted in the kernels' folder is not imported; the fallback
folder in the temporary directory is the user's alone. Runs that need a fresh cache state
(loaded kernels, numba's dispatchers) are subprocesses with ``WORKBENCH_CACHE_DIR`` in
``tmp_path``."""

import importlib.util
import marshal
import os
import pickle
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import pytest

from workbench import _cache

ROOT = Path(__file__).resolve().parents[2]
SHARED = "WORKBENCH_SHARED_CACHE"

PLACEHOLDER = """
import numpy as np
import workbench
from workbench.solver._templates.placeholder_hooks import rhs

rhs(0.0, np.ones(2), np.zeros(0), np.zeros(0, np.int64), np.zeros(0), np.zeros(1), np.empty(2))
print(sum(rhs.stats.cache_hits.values()), sum(rhs.stats.cache_misses.values()))
"""


class _Marker:
    """A pickle that creates a file when it is unpickled: planted code."""

    def __init__(self, path: Path) -> None:
        self.path = str(path)

    def __reduce__(self):
        return (open, (self.path, "w"))


def _env(cache: Path) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", SHARED)}
    env.update(WORKBENCH_CACHE_DIR=str(cache), PYTHONPATH=str(ROOT))
    return env


def _plant(path: Path, marker: Path, index: bool) -> None:
    """Replace numba's index (a numba version, then a pickle) or data file (a pickle) by a
    pickle that creates ``marker``; checked to work here first."""
    payload = pickle.dumps(_Marker(marker))
    pickle.loads(payload)
    assert marker.exists()  # the plant is live code
    marker.unlink()
    with open(path, "wb") as f:
        if index:
            pickle.dump(numba.__version__, f)  # numba compares it, then unpickles the rest
        f.write(payload)


def _python(script: str, env: dict, cwd: Path, check: bool = True) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(script)],
        cwd=cwd,
        env=env,
        capture_output=True,
        text=True,
        check=check,
    )


def _hits_misses(out: subprocess.CompletedProcess) -> tuple[int, int]:
    hits, misses = out.stdout.split()
    return int(hits), int(misses)


@pytest.mark.parametrize("planted", ["index", "data"])
def test_a_pickle_planted_in_a_workbench_functions_cache_does_not_run(tmp_path, planted):
    """A compiled workbench function (the placeholder hooks' ``rhs``: seconds to compile): its
    index (``.nbi``, a numba version then a pickle) or its data file (``.nbc``) replaced by a
    pickle that creates a file. The next process does not create it, compiles the function
    again with one notice, and the one after loads it from the cache without a word."""
    cache, marker = tmp_path / "cache", tmp_path / "planted-code-ran"
    env = _env(cache)
    assert _hits_misses(_python(PLACEHOLDER, env, tmp_path)) == (0, 1)  # compiled
    assert _hits_misses(_python(PLACEHOLDER, env, tmp_path)) == (1, 0)  # loaded
    suffix = ".nbi" if planted == "index" else ".nbc"
    (target,) = cache.rglob(f"placeholder_hooks.rhs-*{suffix}")
    _plant(target, marker, planted == "index")
    out = _python(PLACEHOLDER, env, tmp_path, check=False)
    assert not marker.exists()
    assert out.returncode == 0, out.stderr
    assert _hits_misses(out) == (0, 1)  # compiled again, not loaded
    notices = [line for line in out.stderr.splitlines() if "CacheWarning" in line]
    assert len(notices) == 1 and str(target) in notices[0], out.stderr
    assert "does not match the digest recorded" in notices[0]
    again = _python(PLACEHOLDER, env, tmp_path)
    assert _hits_misses(again) == (1, 0) and "CacheWarning" not in again.stderr
    assert not marker.exists()


@pytest.mark.slow
def test_a_pickle_planted_in_a_kernels_index_does_not_run_on_the_next_workbench_run(tmp_path):
    """The finding itself: ``workbench run`` of the Duffing study, a pickle planted in the index
    of its kernel's loop (``kernel_workbench_models_duffing_*.advance-*.nbi``), ``workbench run``
    again: the planted code does not run; the kernel is compiled again with one warning."""
    cache, marker = tmp_path / "cache", tmp_path / "planted-code-ran"
    env = _env(cache)
    study = str(ROOT / "studies" / "duffing.toml")

    def run(check: bool = True) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "workbench.cli", "run", study, "-o", "d.nc", "--overwrite"],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            check=check,
        )

    run()
    (index,) = cache.rglob("kernel_workbench_models_duffing_*.advance-*.nbi")
    _plant(index, marker, True)
    out = run(check=False)
    assert not marker.exists()
    assert out.returncode == 0, out.stderr
    warnings = [line for line in out.stderr.splitlines() if "warning:" in line]
    assert len(warnings) == 1 and str(index) in warnings[0], out.stderr
    assert "compiling the duffing kernel" in out.stderr
    assert "compiling" not in run().stderr  # recorded anew: loaded, silently


def _refusal(monkeypatch, root: Path, shared: str | None = None) -> str | None:
    """Why ``_cache`` refuses ``root`` as WORKBENCH_CACHE_DIR (None: it uses it)."""
    monkeypatch.setenv("WORKBENCH_CACHE_DIR", str(root))
    if shared is None:
        monkeypatch.delenv(SHARED, raising=False)
    else:
        monkeypatch.setenv(SHARED, shared)
    location = _cache._locate()
    assert location.path == root
    return location.refusal


@pytest.mark.parametrize(
    ("mode", "owner", "shared", "refused"),
    [
        (0o700, None, None, None),
        (0o755, None, None, None),
        (0o777, None, None, "mode 0777) is writable by every user, so compiled code found there"),
        (0o775, None, None, "mode 0775) is writable by its group, so compiled code found there"),
        (0o755, 12345, None, "(owner uid 12345, mode 0755) is not yours (you are "),
        (0o775, 12345, "1", None),  # a team's cache, by the opt-in
        (0o777, None, "1", "mode 0777) is writable by every user"),  # even so
        (0o700, None, "yes", "WORKBENCH_SHARED_CACHE: got 'yes'; allowed: 1"),
    ],
    ids=["700", "755", "777", "775", "755-theirs", "775-theirs-shared", "777-shared", "bad-opt-in"],
)
def test_a_cache_root_that_is_not_the_users_alone_is_refused(
    tmp_path, monkeypatch, mode, owner, shared, refused
):
    """Mode 777, 775 (group) or another owner: refused, one line with the fix; a group's folder
    with WORKBENCH_SHARED_CACHE=1 (its group trusted); never one that everybody can write."""
    root = tmp_path / "cache"
    root.mkdir()
    root.chmod(mode)
    if owner is not None:
        os.chown(root, owner, -1)
    refusal = _refusal(monkeypatch, root, shared)
    if refused is None:
        assert refusal is None
        assert (root / "digests").is_dir()
        return
    assert refused in refusal and "\n" not in refusal
    fix = {0o777: f"chmod o-w {root}", 0o775: f"chmod go-w {root}"}.get(mode, "")
    if owner or mode != 0o700:
        assert fix in refusal and "set WORKBENCH_CACHE_DIR to a folder of your own" in refusal
    assert not (root / "digests").exists()  # nothing written into a refused cache


def test_a_digests_folder_that_others_can_write_is_refused(tmp_path, monkeypatch):
    """The records of what workbench compiled are as private as the cache: who could write
    them could vouch for planted files."""
    root = tmp_path / "cache"
    (root / "digests").mkdir(parents=True)
    root.chmod(0o700)
    (root / "digests").chmod(0o777)
    refusal = _refusal(monkeypatch, root)
    assert "digests folder" in refusal and "writable by every user" in refusal
    (root / "digests").chmod(0o700)
    (root / "digests").rename(root / "elsewhere")
    (root / "digests").symlink_to(root / "elsewhere")
    assert "is a link" in _refusal(monkeypatch, root)


@pytest.mark.parametrize("command", ["run", "campaign"])
def test_a_refused_cache_is_one_line_of_the_command_with_the_fix(tmp_path, command):
    """``workbench run`` (or ``campaign``) with a cache of mode 777: exit code 2, one line on
    stderr, before anything runs, that names the folder, its owner and mode and the fix; no
    traceback; nothing written into the cache, no output or campaign store."""
    cache = tmp_path / "cache"
    cache.mkdir()
    cache.chmod(0o777)
    scene = tmp_path / "scene.toml"
    sweep = (
        "\n[sweep]\ngamma = { start = 0.3, stop = 0.5, num = 2 }\n" if command == "campaign" else ""
    )
    scene.write_text(f'[model]\nname = "duffing"\n[run]\ncycles = 2\n{sweep}')
    out = subprocess.run(
        [sys.executable, "-m", "workbench.cli", command, str(scene), "-o", "d.nc"],
        cwd=tmp_path,
        env=_env(cache),
        capture_output=True,
        text=True,
    )
    assert out.returncode == 2, out.stderr
    me = _cache._owner(os.geteuid())
    assert out.stderr.splitlines() == [
        f"workbench {command}: error: the kernel cache {cache} (owner {me}, mode 0777) is "
        "writable by every user, so compiled code found there could be anyone's; chmod o-w "
        f"{cache} (go-w if it is yours alone), or set WORKBENCH_CACHE_DIR to a folder of "
        "your own"
    ]
    assert list(cache.iterdir()) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache", "scene.toml"]


def _without_home(monkeypatch, tmp_path: Path) -> Path:
    """A home that cannot hold a cache (a file) and a temporary directory of the test's own."""
    (tmp_path / "home").write_text("")
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    monkeypatch.delenv("WORKBENCH_CACHE_DIR", raising=False)
    monkeypatch.delenv("WORKBENCH_SHARED_CACHE", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setattr("tempfile.tempdir", str(temporary))
    return temporary


def test_the_temporary_fallback_is_the_users_alone_and_found_again(tmp_path, monkeypatch):
    """With the home not writable: folders named like the user's fallback but owned by another
    uid, or of mode 777, or a link to a folder of the user's, are not used; a new one is made
    (mode 0700, an unpredictable name), said once, and the next process finds it again."""
    temporary = _without_home(monkeypatch, tmp_path)
    prefix = f"workbench-cache-{os.geteuid()}-"
    theirs, wide, link = (temporary / f"{prefix}{n}" for n in ("aaaa", "bbbb", "cccc"))
    for folder in (theirs, wide, tmp_path / "mine"):
        folder.mkdir(mode=0o700)
    os.chown(theirs, 12345, -1)
    wide.chmod(0o777)
    link.symlink_to(tmp_path / "mine")  # a private folder of mine, but reached by a link

    first = _cache._locate()
    assert first.refusal is None and first.path.parent == temporary
    assert first.path not in (theirs, wide, link)
    assert first.path.name.startswith(prefix) and len(first.path.name) > len(prefix) + 4
    st = os.lstat(first.path)
    assert st.st_uid == os.geteuid() and (st.st_mode & 0o777) == 0o700
    assert "ignored 3 folder(s)" in first.notice and str(first.path) in first.notice
    assert _cache._locate().path == first.path  # found again
    assert {p.name for p in temporary.iterdir()} == {
        p.name for p in (theirs, wide, link, first.path)
    }


def test_a_fallback_made_wider_or_given_away_is_not_used_again(tmp_path, monkeypatch):
    temporary = _without_home(monkeypatch, tmp_path)
    first = _cache._locate().path
    first.chmod(0o777)
    second = _cache._locate().path
    assert second != first and second.parent == temporary
    os.chown(second, 12345, -1)
    third = _cache._locate().path
    assert third not in (first, second)


KERNEL = """
import sys
import workbench
from workbench.solver._compile import jacobian_for

module = jacobian_for("workbench.models.duffing")
print(module.__name__.split(".")[1], module.__file__)
"""


def _kernel(cache: Path, tmp_path: Path) -> subprocess.CompletedProcess:
    return _python(KERNEL, _env(cache), tmp_path)


def test_a_package_planted_in_place_of_a_kernel_module_is_not_imported(tmp_path):
    """A folder ``kernels/<module>/`` with an ``__init__.py`` (which Python's path finder prefers
    to ``<module>.py``) is ignored with a warning; the module is the generated one."""
    cache, marker = tmp_path / "cache", tmp_path / "planted-code-ran"
    name, file = _kernel(cache, tmp_path).stdout.split()
    package = cache / "kernels" / name
    package.mkdir()
    (package / "__init__.py").write_text(f"open({str(marker)!r}, 'w').close()\n")
    out = _kernel(cache, tmp_path)
    assert not marker.exists()
    assert out.stdout.split() == [name, file]
    assert f"{package} is a folder named like the generated module" in out.stderr


def test_bytecode_planted_for_a_kernel_module_is_not_imported(tmp_path):
    """A ``__pycache__`` entry of a kernel module, stamped with the ``.py`` file's modification
    time and size as Python's import checks it, holding other code: not loaded."""
    cache, marker = tmp_path / "cache", tmp_path / "planted-code-ran"
    name, file = _kernel(cache, tmp_path).stdout.split()
    source = Path(file)
    st = source.stat()
    code = compile(f"open({str(marker)!r}, 'w').close()\n", file, "exec")
    pyc = Path(importlib.util.cache_from_source(file))
    pyc.parent.mkdir(exist_ok=True)
    header = importlib.util.MAGIC_NUMBER + (0).to_bytes(4, "little")
    header += int(st.st_mtime).to_bytes(4, "little") + (st.st_size & 0xFFFFFFFF).to_bytes(
        4, "little"
    )
    pyc.write_bytes(header + marshal.dumps(code))
    _kernel(cache, tmp_path)
    assert not marker.exists()


FOLDER = """
import workbench
from workbench._cache import CacheError
from workbench.solver._compile import jacobian_for

try:
    jacobian_for("workbench.models.duffing")
except CacheError as exc:
    print(exc)
"""


def test_a_folder_in_place_of_a_kernel_module_file_is_refused_in_one_line(tmp_path):
    cache = tmp_path / "cache"
    name, file = _kernel(cache, tmp_path).stdout.split()
    Path(file).unlink()
    Path(file).mkdir()
    out = _python(FOLDER, _env(cache), tmp_path)
    assert out.stdout.strip() == (
        f"{file} is a folder where workbench writes a generated kernel module; remove it "
        "(workbench never imports it)"
    )


def test_compiled_code_that_cannot_be_saved_leaves_the_function_uncached(tmp_path, monkeypatch):
    """A save that fails (here: a file where numba's folder should be; a full disk, a shared
    cache whose folders the group cannot write) is one notice, not a failed run."""
    root = tmp_path / "cache"
    monkeypatch.setenv("WORKBENCH_CACHE_DIR", str(root))
    monkeypatch.setattr(_cache, "_found", [_cache._locate()])
    blocked = root / "numba" / "not-a-folder"
    blocked.parent.mkdir()
    blocked.write_text("")
    monkeypatch.setattr(_cache, "_CLAIMED", {str(blocked)})
    monkeypatch.setattr(_cache, "_announced", set())
    index = _cache.CheckedIndexDataCacheFile(str(blocked), "f-1.py311", "stamp")
    with pytest.warns(_cache.CacheWarning, match="cannot be written to the kernel cache"):
        index.save(("signature",), ("compiled",))
    assert index._load_index() == {}
