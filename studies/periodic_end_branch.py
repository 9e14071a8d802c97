"""The nine-bar's impacting period-1 orbit continued in omega to the end of its branch.

Fig. 32's scene (``studies/bifurcation_speed/sweep.toml``: c = 0.1 mm at A and B, c_f = 0.01).
Past the grazing near 1.843 pi, where the lasting contact first lifts off, the period-1 orbit
impacts; this script finds it from a transient at ``--start`` (Newton's method on the
stroboscopic map at ``--rtol``), continues it with :func:`workbench.continuation.continue_orbit`
up to ``--stop`` and prints every point (parameter in units of pi, label, events per joint,
largest multipliers) and every located bifurcation (kind, parameter, critical multiplier,
transition at a grazing). ``-o`` keeps the branch as netCDF.

Run (one core; near the end of the branch its steps collapse at nonsmooth points of the map,
each failed correction costing eight evaluations of the map with its monodromy matrix)::

    python studies/periodic_end_branch.py --start 1.86105 --stop 1.8612 -o branch.nc

(``data/periodic_end_branch.nc`` is that run: the end of the 40-event orbit, a lift-off
grazing typed a border collision, docs/continuation.md.)

``--scene studies/periodic_end_hunt_crossley.toml`` follows the same branch under the
Hunt-Crossley law (no memory).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

import workbench
from workbench.continuation import branch_bifurcations, continue_orbit

SCENE = Path(__file__).resolve().parent / "bifurcation_speed" / "sweep.toml"
#: points at most per branch: the lasting-contact orbit from pi to its lift-off near 1.843 pi
#: needs more than 400 (its strobe velocities loop with omega, the phase of a fast oscillation
#: along the bearing's wall, docs/continuation.md)
MAX_POINTS = 800


def branch(
    start: float,
    stop: float,
    *,
    scene_path: Path = SCENE,
    rtol: float = 1e-10,
    tolerance: float = 1e-6,
    transient: int = 200,
    max_step: float = 1.0,
    max_points: int = MAX_POINTS,
    progress: bool = False,
):
    """The period-1 branch of Fig. 32's scene from ``start`` to ``stop`` (rad/s), its first orbit
    found by Newton's method from the state after ``transient`` forcing periods from rest."""
    scene = workbench.load_scene(scene_path).replace(sweep={})
    point = scene.replace(run={"cycles": 1, "transient_cycles": transient}).with_parameters(
        omega=start
    )
    return continue_orbit(
        point,
        "omega",
        stop=stop,
        rtol=rtol,
        tolerance=tolerance,
        max_step=max_step,
        max_points=max_points,
        progress=progress,
    )


def table(r) -> list[str]:
    """One line per point and per located bifurcation."""
    lines = []
    flags = r.label.attrs["flag_meanings"].split()
    for i in range(r.sizes["point"]):
        mu = r.multiplier_real.values[i] + 1j * r.multiplier_imag.values[i]
        mu = mu[np.isfinite(mu)][:2]
        cr = r.crossings_per_orbit.values[i].tolist() if "crossings_per_orbit" in r else []
        lines.append(
            f"{float(r.omega[i]) / math.pi:.9f} pi  {flags[int(r.label[i])]:15s} "
            f"events {int(r.events_per_period[i]):3d} crossings {cr} "
            f"mu {' '.join(f'{m.real:+.4f}{m.imag:+.4f}j' for m in mu)}"
        )
    for b in branch_bifurcations(r, "omega"):
        lines.append(f"bifurcation {b['type']} at {b['value'] / math.pi:.9f} pi: {b}")
    lines.append(f"ended: {r.attrs['branch_ended']}")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument(
        "--scene", type=Path, default=SCENE, help="the scene (default: Fig. 32's, LN contact)"
    )
    ap.add_argument("--start", type=float, default=1.855, help="omega / pi at the start")
    ap.add_argument("--stop", type=float, default=1.87, help="omega / pi at the stop")
    ap.add_argument("--rtol", type=float, default=1e-10)
    ap.add_argument("--tolerance", type=float, default=1e-6, help="Newton's (scaled)")
    ap.add_argument("--transient", type=int, default=200, help="forcing periods from rest")
    ap.add_argument("--max-step", type=float, default=1.0, help="scaled arclength")
    ap.add_argument("--max-points", type=int, default=MAX_POINTS)
    ap.add_argument("-o", "--output", type=Path, help="netCDF of the branch")
    a = ap.parse_args()
    t0, w0 = time.process_time(), time.time()
    r = branch(
        a.start * math.pi,
        a.stop * math.pi,
        scene_path=a.scene,
        rtol=a.rtol,
        tolerance=a.tolerance,
        transient=a.transient,
        max_step=a.max_step,
        max_points=a.max_points,
        progress=True,
    )
    print(
        f"cpu {time.process_time() - t0:.1f} s, wall {time.time() - w0:.1f} s, "
        f"{r.sizes['point']} points, {r.attrs['map_evaluations']} map evaluations, rtol "
        f"{r.attrs['rtol']:g}, tolerance {r.attrs['tolerance']:g}, noise {r.attrs['map_noise']:.3g}"
    )
    r.attrs.update(
        measured_cpu_time=time.process_time() - t0,
        measured_wall_time=time.time() - w0,
        command="python studies/periodic_end_branch.py "
        + f"--start {a.start:g} --stop {a.stop:g} --rtol {a.rtol:g}",
    )
    if a.output is not None:
        workbench.save_run(r, a.output)
    print("\n".join(table(r)))


if __name__ == "__main__":
    main()
