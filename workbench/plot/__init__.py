"""Figures (PNG, labelled axes with units) of runs, campaigns, studies and analyses.

Every function returns a :class:`matplotlib.figure.Figure` (or writes PNG files and returns their
paths); nothing is shown on screen.
"""

from workbench.plot._accuracy import work_precision_figure
from workbench.plot._analysis import (
    bifurcation_figure,
    embedding_figure,
    lle_figure,
    phase_figure,
    poincare_figure,
    zero_one_figure,
)
from workbench.plot._base import display_scale, register_overview, wrap_title
from workbench.plot._failures import failure_note, mark_failed, run_status_note
from workbench.plot._phase import (
    CoarseSamplingWarning,
    coarse_sampling,
    run_phase_figure,
    run_poincare_figure,
)
from workbench.plot._runs import (
    PANELS_PER_FIGURE,
    campaign_figure,
    run_figure_names,
    run_figures,
    timeseries_figure,
)
from workbench.plot._stability import floquet_figure, jacobian_spectrum_figure
from workbench.plot._verify import verification_figure

__all__ = [
    "PANELS_PER_FIGURE",
    "CoarseSamplingWarning",
    "coarse_sampling",
    "display_scale",
    "failure_note",
    "mark_failed",
    "run_phase_figure",
    "run_poincare_figure",
    "run_status_note",
    "wrap_title",
    "bifurcation_figure",
    "campaign_figure",
    "embedding_figure",
    "floquet_figure",
    "jacobian_spectrum_figure",
    "lle_figure",
    "phase_figure",
    "poincare_figure",
    "register_overview",
    "run_figure_names",
    "run_figures",
    "timeseries_figure",
    "verification_figure",
    "work_precision_figure",
    "zero_one_figure",
]
