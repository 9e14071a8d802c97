"""What several test modules share: the mechanisms' energy balance and the spec's numbers."""

import math

import xarray as xr

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
