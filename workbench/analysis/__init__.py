"""Analysis of runs: phase portraits, Poincaré sections, delay and embedding selection, largest
Lyapunov exponents (Wolf et al. 1985; Rosenstein et al. 1993 via nolds; from the equations,
Benettin et al. 1980: two trajectories, and the spectrum from the variational equations with
saltation at events; the largest one by protocol, :func:`largest_exponent`), the 0-1 test
for chaos and bifurcation diagrams (with where a sweep's period-1 motion ends,
:func:`periodic_run_end`); a series with nothing to analyse (:func:`no_dynamics`)
and one that cannot be told from linear noise (:func:`surrogate_test`) are said so.

Every estimator accepts numpy arrays and xarray DataArrays (a ``time`` coordinate gives dt) and
returns an ``xarray.Dataset`` with units: the chosen value and the evidence behind it. The
estimators of one series (0-1 test, delays, embedding dimensions, Wolf's and Rosenstein's
exponents) also take a DataArray with more dims, e.g. a campaign's record, and map over every
dim but the series' own, lazily on a dask-backed one (``_broadcast``): ``zero_one_test(
campaign.x)`` has ``K`` over the campaign's parameters.

>>> import numpy as np
>>> from workbench.analysis import delay_acf
>>> int(delay_acf(np.sin(0.05 * np.arange(4000)), rule="zero").delay)  # a quarter period
32
"""

from workbench.analysis import _delay, _embedding, _rosenstein, _wolf, _zero_one
from workbench.analysis._benettin import lle_from_equations
from workbench.analysis._bifurcation import bifurcation_diagram, periodic_run_end
from workbench.analysis._broadcast import over_parameters
from workbench.analysis._convergence import ConvergenceWarning
from workbench.analysis._degenerate import no_dynamics
from workbench.analysis._embedding import embed
from workbench.analysis._exponent import LargestExponent, largest_exponent
from workbench.analysis._lyapunov import lyapunov_spectrum
from workbench.analysis._sections import crossing_section, phase_portrait, poincare_section
from workbench.analysis._stability import floquet, floquet_sweep, jacobian_spectrum
from workbench.analysis._surrogate import surrogate_test

# estimators of one series, mapped over every other dim of a DataArray
delay_acf = over_parameters(_delay.delay_acf)
delay_ami = over_parameters(_delay.delay_ami)
embedding_cao = over_parameters(_embedding.embedding_cao)
embedding_fnn = over_parameters(_embedding.embedding_fnn)
rosenstein_lle = over_parameters(_rosenstein.rosenstein_lle)
wolf_lle = over_parameters(_wolf.wolf_lle)
zero_one_test = over_parameters(_zero_one.zero_one_test)

__all__ = [
    "ConvergenceWarning",
    "LargestExponent",
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
    "largest_exponent",
    "lle_from_equations",
    "lyapunov_spectrum",
    "no_dynamics",
    "periodic_run_end",
    "phase_portrait",
    "poincare_section",
    "rosenstein_lle",
    "surrogate_test",
    "wolf_lle",
    "zero_one_test",
]
