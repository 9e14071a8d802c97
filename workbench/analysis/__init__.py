"""Analysis of runs: phase portraits, Poincaré sections, delay and embedding selection, largest
Lyapunov exponents (Wolf et al. 1985; Rosenstein et al. 1993 via nolds; from the equations,
Benettin et al. 1980: two trajectories, and the spectrum from the variational equations with
saltation at events), the 0-1 test for chaos and bifurcation diagrams; a series with nothing to
analyse (:func:`no_dynamics`) and one that cannot be told from linear noise
(:func:`surrogate_test`) are said so.

Every estimator accepts numpy arrays and xarray DataArrays (a ``time`` coordinate gives dt) and
returns an ``xarray.Dataset`` with units: the chosen value and the evidence behind it.

>>> import numpy as np
>>> from workbench.analysis import delay_acf
>>> int(delay_acf(np.sin(0.05 * np.arange(4000)), rule="zero").delay)  # a quarter period
32
"""

from workbench.analysis._benettin import lle_from_equations
from workbench.analysis._bifurcation import bifurcation_diagram
from workbench.analysis._degenerate import no_dynamics
from workbench.analysis._delay import delay_acf, delay_ami
from workbench.analysis._embedding import embed, embedding_cao, embedding_fnn
from workbench.analysis._lyapunov import lyapunov_spectrum
from workbench.analysis._rosenstein import rosenstein_lle
from workbench.analysis._sections import crossing_section, phase_portrait, poincare_section
from workbench.analysis._stability import floquet, floquet_sweep, jacobian_spectrum
from workbench.analysis._surrogate import surrogate_test
from workbench.analysis._wolf import wolf_lle
from workbench.analysis._zero_one import zero_one_test

__all__ = [
    "bifurcation_diagram",
    "crossing_section",
    "delay_acf",
    "delay_ami",
    "embed",
    "embedding_cao",
    "embedding_fnn",
    "floquet",
    "floquet_sweep",
    "jacobian_spectrum",
    "lle_from_equations",
    "lyapunov_spectrum",
    "no_dynamics",
    "phase_portrait",
    "poincare_section",
    "rosenstein_lle",
    "surrogate_test",
    "wolf_lle",
    "zero_one_test",
]
