"""Record, then compare, the Datasets of ``wolf_lle`` on nine fixed series: the check that a
refactor of the estimator changed no bit (issue 28 item 4: wolf_lle in stages).

    python benchmarks/wolf_identical.py record /tmp/wolf_before   # on the old code
    python benchmarks/wolf_identical.py compare /tmp/wolf_before  # on the new code: exit 0 if
                                                                   # every Dataset is identical

The series: Henon, logistic with fixed settings, white noise (as a map and with dt = 0.01 s at
amplitude 1e-9), Lorenz x (flow, every 20th sample, forced map), a Duffing section, and the
nine-bar's clearance coordinate x of joint A from data/chaos_run.nc (run from the repository).
"""

import sys
import time

import numpy as np
import xarray as xr

import workbench
from workbench.analysis import poincare_section, wolf_lle


def henon(n=3000):
    x = np.empty(n)
    a, b = 0.1, 0.0
    for i in range(n):
        a, b = 1 - 1.4 * a * a + b, 0.3 * a
        x[i] = a
    return x[100:]


def logistic(n=3000):
    x = np.empty(n)
    a = 0.3
    for i in range(n):
        a = 4 * a * (1 - a)
        x[i] = a
    return x[100:]


def cases():
    rng = np.random.default_rng(1)
    lor = workbench.simulate(
        {
            "model": {"name": "lorenz"},
            "run": {"duration": 200.0, "transient": 20.0},
            "record": {"dt": 0.01},
        }
    )
    duf = workbench.simulate(
        {
            "model": {"name": "duffing"},
            "run": {"cycles": 1000, "transient_cycles": 50},
            "record": {"samples_per_period": 1},
        }
    )
    chaos = workbench.open_run("data/chaos_run.nc")
    yield "henon", lambda: wolf_lle(henon())
    yield "logistic_fixed", lambda: wolf_lle(logistic(), dim=2, delay=1, evolve=1, theiler=3)
    yield "noise", lambda: wolf_lle(rng.standard_normal(4000))
    yield (
        "noise_dt",
        lambda: wolf_lle(1e-9 * np.random.default_rng(2).standard_normal(3001), dt=0.01),
    )
    yield "lorenz", lambda: wolf_lle(lor.x)
    yield "lorenz_coarse", lambda: wolf_lle(lor.x[::20])
    yield "lorenz_map", lambda: wolf_lle(lor.x, flow=False, scale_max=2.0, max_angle=0.5)
    yield "duffing_section", lambda: wolf_lle(poincare_section(duf, "x").x)
    yield (
        "ninebar_x1",
        lambda: wolf_lle(chaos.clearance_x.sel(joint="A"), period=chaos.attrs["forcing_period"]),
    )


mode, path = sys.argv[1], sys.argv[2]
out = {}
for name, f in cases():
    t = time.process_time()
    r = f()
    print(name, float(r.lle), int(r.reliable), f"{time.process_time() - t:.2f} s CPU", flush=True)
    out[name] = r
if mode == "record":
    for name, r in out.items():
        r.to_netcdf(f"{path}_{name}.nc")
else:
    bad = 0
    for name, r in out.items():
        old = xr.open_dataset(f"{path}_{name}.nc").load()
        r.to_netcdf(f"{path}_new.nc")  # through the same encoding as the record
        new = xr.open_dataset(f"{path}_new.nc").load()
        try:
            xr.testing.assert_identical(old, new)
            print(name, "identical")
        except AssertionError as e:
            bad += 1
            print(name, "DIFFERS", str(e)[:2000])
    sys.exit(bad)
