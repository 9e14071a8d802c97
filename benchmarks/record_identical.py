"""Record, then compare, every recorded variable of the mechanisms' default scenes: the check
that a refactor of the record-time evaluation (``workbench.models._record``) changed no bit
(issue 28 item 4: ``_record``'s arguments grouped).

    python benchmarks/record_identical.py record /tmp/record_before.npz   # on the old code
    python benchmarks/record_identical.py compare /tmp/record_before.npz  # on the new code: exit
                                                                           # 0 if all are equal
                                                      # (a record in benchmarks/records/)

The scenes, 2 cycles from rest each: the nine-bar's default scene (studies/ninebar.toml: joints
A and B, 0.5 mm, omega = 2.5 pi) with modified Coulomb and with LuGre friction, and the ideal
nine-bar (no clearance); the slider-crank's default scene (the model's defaults: joint B, no
friction, 5000 rpm) and the same with Coulomb and with LuGre friction (c_f = 0.05). Every data
variable and coordinate of each run is compared with ``np.array_equal`` (NaN equal to NaN).
"""

import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
from _results import recording  # benchmarks/_results.py: a JSON record per run

import workbench

NINEBAR = Path(__file__).resolve().parents[1] / "studies" / "ninebar.toml"
RUN = {"cycles": 2, "transient_cycles": 0}


def scenes():
    """(name, scene) of every case."""
    nine = tomllib.loads(NINEBAR.read_text())
    for name, effects in (
        ("ninebar_coulomb", {"friction": "coulomb"}),
        ("ninebar_lugre", {"friction": "lugre"}),
        ("ninebar_ideal", {"clearance": []}),
    ):
        yield name, {**nine, "effects": {**nine["effects"], **effects}, "run": RUN}
    crank = {"model": {"name": "slider_crank"}, "run": RUN}
    yield "slider_crank", crank
    for friction in ("coulomb", "lugre"):
        yield (
            f"slider_crank_{friction}",
            {
                **crank,
                "effects": {"clearance": ["B"], "friction": friction},
                "parameters": {"friction_coefficient": 0.05},  # the default is 0
            },
        )


def arrays() -> dict[str, np.ndarray]:
    """``scene/variable`` -> values of every data variable and coordinate of every run."""
    out = {}
    for name, scene in scenes():
        t = time.process_time()
        ds = workbench.simulate(scene)
        for v in [*ds.data_vars, *ds.coords]:
            out[f"{name}/{v}"] = ds[v].values
        print(
            f"{name}: {ds.sizes['time']} records, {len(ds.data_vars)} variables, "
            f"{time.process_time() - t:.1f} s CPU",
            flush=True,
        )
    return out


def code_version() -> str:
    """The commit of the ``workbench`` package that runs (``-dirty`` if its files differ from
    it) and its directory: the baseline says which code recorded it."""
    root = Path(workbench.__file__).resolve().parents[1]

    def git(*args: str) -> str:
        out = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True)
        return out.stdout.strip()

    sha = git("rev-parse", "--short", "HEAD") or "unknown"
    dirty = git("status", "--porcelain", "--untracked-files=no", "--", "workbench")
    return f"{sha}{'-dirty' if dirty else ''} ({root})"


def main(mode: str, path: str) -> int:
    version = code_version()
    print(f"workbench {version}")
    new = arrays()
    if mode == "record":
        np.savez(path, **new, _recorded_by=np.array(version))
        print(f"recorded {len(new)} arrays in {path}")
        return 0
    with np.load(path) as f:
        old = {k: f[k] for k in f.files}
    print(f"baseline {path}: workbench {old.pop('_recorded_by', 'unknown')}")
    bad = sorted(set(old) ^ set(new))
    for k in sorted(set(old) & set(new)):
        a, b = old[k], new[k]
        nan = a.dtype.kind == "f"
        if a.dtype != b.dtype or not np.array_equal(a, b, equal_nan=nan):
            bad.append(k)
    print(f"{len(new)} arrays compared, {len(old)} recorded: {len(bad)} differ {bad}")
    return 1 if bad else 0


if __name__ == "__main__":
    if sys.argv[1] == "compare":  # the comparison is recorded, not the baseline
        with recording(__file__):
            code = main(sys.argv[1], sys.argv[2])
        sys.exit(code)
    sys.exit(main(sys.argv[1], sys.argv[2]))
