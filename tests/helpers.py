"""What several test modules share: the mechanisms' energy balance, the spec's numbers and the
flow map's derivative two ways (tangent system, copies)."""

import contextlib
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from workbench.solver import integrate
from workbench.solver._copies import copies_problem, split_copies
from workbench.solver._tangent import state_scale, tangent_columns, tangent_problem

#: a stop oscillator of benchmarks/grazing_audit.py (seed 7, case 4), none of the suite's other
#: sets (SI units): a stiff stop (k_s / k = 683) whose contact past the grazing near 1.65569 rad/s
#: lasts 0.4 % of the period, shorter than a DOP853 step at rtol 1e-9
STIFF_STOP = {
    "mass": 0.5892006969339904,
    "damping": 0.25448732539838487,
    "stiffness": 2.3021108709497957,
    "stop_stiffness": 1572.0334472993243,
    "gap": 0.8268228231033374,
    "force": 0.6663036290419094,
}

# the energy quadratures and energies a mechanism records for its balance
ENERGY = ["driver_work", "dissipated_energy", "kinetic_energy", "potential_energy"]

# Ideal joints: peak slider speed (m s-1) and acceleration (m s-2) of the nine-bar at each crank
# speed (rad s-1), from "Numbers to check" of docs/ninebar-parameters.md.
IDEAL_SLIDER_PEAKS = [
    (math.pi, 0.638, 3.39),
    (2 * math.pi, 1.277, 13.56),
    (2.5 * math.pi, 1.596, 21.19),
    (4 * math.pi, 2.553, 54.25),
]


def energy_residual(ds: xr.Dataset) -> xr.DataArray:
    """Driver work minus dissipated energy minus the change of kinetic and potential energy
    since the first record (J): zero for an exact run of a mechanism."""
    return (
        ds.driver_work
        - ds.dissipated_energy
        - (ds.kinetic_energy - ds.kinetic_energy[0])
        - (ds.potential_energy - ds.potential_energy[0])
    )


#: how many combined standard errors two estimates of one chaotic or statistical quantity may
#: differ by: about a 0.3 % chance for two independent Gaussian estimates of the same value
AGREE_SIGMAS = 3.0


def agrees(value: float, error: float, quoted: float, quoted_error: float) -> bool:
    """Whether an estimate and a quoted one (each with its standard error) agree within
    AGREE_SIGMAS combined errors: how a chaotic or statistical number computed now is checked
    against the figure a page quotes, which another processor computed (its rounding sends a
    chaotic trajectory elsewhere within a few periods: the digits differ, the value does not)."""
    return abs(value - quoted) <= AGREE_SIGMAS * math.hypot(error, quoted_error)


def flow_map_tangent(pb, t1, rtol):
    """d y(t1) / d y(t0) from the tangent system (columns: unit perturbations of each state)."""
    n, na = pb.y0.size, pb.aux0.size
    s = state_scale(pb)
    V = np.zeros((n + na, n))
    V[:n] = np.diag(s)
    res = integrate(tangent_problem(pb, V), np.array([t1]), rtol=rtol, atol=rtol)
    _, V, log_det = tangent_columns(res.Y[-1], n, na, n)
    return V[:n] / s[None, :], log_det, res.stats["events"]


def flow_map_copies(pb, t1, rtol, h=1e-6):
    """d y(t1) / d y(t0) by central differences of copies integrated side by side (one step
    sequence, so that their integration errors cancel in the differences)."""
    n = pb.y0.size
    s = state_scale(pb)
    Y = np.repeat(pb.y0[None, :], 2 * n, axis=0)
    for j in range(n):
        Y[2 * j, j] += h * s[j]
        Y[2 * j + 1, j] -= h * s[j]
    AUX = np.repeat(pb.aux0[None, :], 2 * n, axis=0)
    res = integrate(copies_problem(pb, Y, AUX), np.array([t1]), rtol=rtol, atol=rtol)
    Yt, _, _, _ = split_copies(res.Y[-1], res.AUX[-1], 2 * n)
    return np.column_stack([(Yt[2 * j] - Yt[2 * j + 1]) / (2 * h * s[j]) for j in range(n)])


@contextlib.contextmanager
def tiny_tmpfs(path: Path, size: str = "1m"):
    path.mkdir()
    try:
        done = subprocess.run(
            ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
            capture_output=True,
        )
    except OSError:
        done = None
    if done is None or done.returncode != 0:
        pytest.skip("mounting a tmpfs needs root")
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], check=False)


#: attributes of a campaign archive that describe one execution (when, how fast, by whom), not
#: its numbers
CAMPAIGN_EXECUTION_ATTRS = (
    "history",
    "computed_blocks",
    "reused_blocks",
    "campaign_wall_time",
    "campaign_compute_wall_time",
    "campaign_cpu_time",
    "resume_cpu_time",
    "campaign_workers",
    "campaign_block_sha256",  # the blocks' bytes hold their wall times and worker pids
)


def campaign_numbers(ds: xr.Dataset, also: tuple[str, ...] = ()) -> xr.Dataset:
    """A campaign's data without its wall times and without the attributes of one execution
    (CAMPAIGN_EXECUTION_ATTRS and ``also``)."""
    drop = set(CAMPAIGN_EXECUTION_ATTRS) | set(also)
    out = ds.drop_vars(["point_wall_time", "solver_wall_time"])
    out.attrs = {k: v for k, v in ds.attrs.items() if k not in drop}
    return out
