"""Largest Lyapunov exponent of Lorenz x: workbench's Wolf estimate against nolds.

Lorenz (10, 28, 8/3), x sampled at dt = 0.01 after a 20 s transient, 10 000 and 20 000 points.
For each: ``workbench.analysis.wolf_lle`` with every choice automatic (map or flow detected,
delay, dimension, evolution time, scales, the reliability checks), ``nolds.lyap_r`` with its
defaults, and ``nolds.lyap_r`` tuned (emb_dim 5, lag 16, min_tsep 100, fit over samples
100-400), all in the same run: wall time (an untraced call), peak memory (tracemalloc: Python
allocations, numpy included; a second call) and the error against 0.9056 1/s. Target: under
0.5 s for 10 000 points, under 100 MB for 20 000, at least 10x faster than nolds. (The error
against the exponent of each window is what tests/test_wolf_heldout.py judges; a 100-s window's
own exponent scatters by several % about 0.9056.) Then wolf_lle's verdict on the same run
sampled every 20th point (dt = 0.2 s): flagged.

Then the exponents from the equations, per method with its converged flag and wall time: on
Lorenz (200 s after 10 s) ``lle_from_equations`` (two trajectories, five knob variants, the
variational exponent on the same trajectory) and ``lyapunov_spectrum`` (QR); on the nine-bar
chaos case (studies/chaos/chaos.toml, 4 transient + 3 crank cycles) the same two
(``--skip-ninebar`` leaves it out: several minutes).

Run: ``python benchmarks/lle.py [--skip-ninebar]``.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc
import warnings

import nolds
import numpy as np
from _results import recording  # benchmarks/_results.py: appends to RESULTS.md

import workbench
from workbench.analysis import lle_from_equations, lyapunov_spectrum, wolf_lle

TRUE = 0.9056  # 1/s
DT = 0.01


def measure(f):
    """Value and wall time of one plain call, peak memory of a second, traced call: tracemalloc
    hooks every allocation and slows allocation-heavy Python code (wolf_lle on 10 000 points
    by ~70 %), so it must not run while the time is taken."""
    t0 = time.perf_counter()
    value = f()
    wall = time.perf_counter() - t0
    tracemalloc.start()
    f()
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    return value, wall, peak


def nolds_tuned(x):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, (ks, div, _) = nolds.lyap_r(
            x, emb_dim=5, lag=16, min_tsep=100, trajectory_len=400, debug_data=True
        )
    ks, div = np.asarray(ks), np.asarray(div)
    sel = (ks >= 100) & (ks <= 400) & np.isfinite(div)
    return float(np.polyfit(ks[sel], div[sel], 1)[0]) / DT


def nolds_default(x):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return float(nolds.lyap_r(x)) / DT


def equations(label: str, scene, lyapunov_exponents: int | None) -> None:
    """The exponents from the equations of one scene: value, converged flag, wall time."""
    t0 = time.perf_counter()
    b = lle_from_equations(scene)
    wall_b = time.perf_counter() - t0
    t0 = time.perf_counter()
    v = lyapunov_spectrum(scene, exponents=lyapunov_exponents)
    wall_v = time.perf_counter() - t0
    print(
        f"{label:>10} {'two trajectories':>26} {float(b.lle):9.4f} {str(bool(b.converged)):>9} "
        f"{wall_b:8.1f}   variants {100 * float(b.spread):.2g} %, stderr {float(b.stderr):.3g}"
    )
    print(
        f"{label:>10} {'variational, same run':>26} {float(b.lle_variational):9.4f} "
        f"{'':>9} {'':>8}   differs by {100 * float(b.method_difference):.2g} %"
    )
    print(
        f"{label:>10} {'variational spectrum (QR)':>26} {float(v.exponent[0]):9.4f} "
        f"{str(bool(v.converged[0])):>9} {wall_v:8.1f}   rtol/10: "
        f"{float(v.exponent_tight[0]):.4g}, stderr {float(v.stderr[0]):.3g}, sum "
        f"{float(v.spectrum_sum):.4g} (divergence {float(v.divergence):.4g})"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-ninebar", action="store_true", help="leave out the nine-bar")
    args = parser.parse_args()
    ds = workbench.simulate(
        {
            "model": {"name": "lorenz"},
            "run": {"duration": 200.0, "transient": 20.0},
            "record": {"dt": DT},
            "solver": {"rtol": 1e-10, "atol": 1e-10},
        }
    )
    wolf_lle(ds.x[:2000])  # warm-up (imports, caches)
    print(
        f"{'points':>7} {'estimator':>22} {'LLE 1/s':>9} {'error':>8} {'time s':>8} {'peak MB':>8}"
    )
    for n in (10_000, 20_000):
        x = ds.x[:n]
        rows = [("wolf_lle (automatic)", lambda x=x: float(wolf_lle(x).lle))]
        rows.append(("nolds.lyap_r tuned", lambda x=x: nolds_tuned(x.values)))
        rows.append(("nolds.lyap_r defaults", lambda x=x: nolds_default(x.values)))
        results = {}
        for name, f in rows:
            value, wall, peak = measure(f)
            results[name] = wall
            print(
                f"{n:7d} {name:>22} {value:9.4f} {value / TRUE - 1:+8.1%} {wall:8.2f} {peak:8.1f}"
            )
        ratio = results["nolds.lyap_r tuned"] / results["wolf_lle (automatic)"]
        print(f"{'':7} wolf_lle is {ratio:.1f}x faster than tuned nolds")
        r = wolf_lle(x)
        print(
            f"{'':7} wolf_lle: {r.attrs['series_kind']}, dim {int(r.dim)}, delay {int(r.delay)}, "
            f"evolve {int(r.evolve)}, {int(r.replacements)} replacements, lambda dt "
            f"{float(r.lle_per_sample):.4f}, reliable {bool(r.reliable)}"
        )
    coarse = wolf_lle(ds.x[::20])
    print(
        f"dt = 0.2 s ({coarse.sizes['elapsed']} steps): LLE {float(coarse.lle):.3f} 1/s, reliable "
        f"{bool(coarse.reliable)}: {coarse.reliable.attrs['message'][:110]}..."
    )
    print(f"\n{'system':>10} {'method':>26} {'LLE 1/s':>9} {'converged':>9} {'time s':>8}")
    lorenz = {"model": {"name": "lorenz"}, "run": {"duration": 200.0, "transient": 10.0}}
    equations("Lorenz", lorenz, None)
    if not args.skip_ninebar:
        chaos = workbench.load_scene("studies/chaos/chaos.toml").replace(
            run={"cycles": 3, "transient_cycles": 4}
        )
        equations("nine-bar", chaos, 1)


if __name__ == "__main__":
    with recording(__file__):
        main()
