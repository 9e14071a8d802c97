"""Figures (PNG, labelled axes with units) of runs, campaigns, studies and analyses.

Every ``*_figure`` function returns a :class:`matplotlib.figure.Figure`, and :func:`run_figures`
writes PNG files and returns their paths; nothing is shown on screen. The helpers beside them
return no figure: :func:`display_unit` (the factor and the unit every figure shows a quantity
stored in given units with: lengths in mm, others as stored, the same in every figure),
:func:`coarse_sampling` (the largest jump between records, and when), :func:`wrap_title` (a
title broken into lines), :func:`failure_note` and :func:`run_status_note` (text on failed
points or a failed run), :func:`mark_failed` (marks failed parameter values on given axes and
returns a note), :func:`curve_overlay` (draws a curve of bifurcations in two parameters on
given axes), :func:`periodic_end_overlay` (draws where a continued sweep's period-1 motion
ends) and :func:`run_figure_names` (the file names :func:`run_figures` writes). The
overview figure that :func:`run_figures` adds for a model is the model's to declare
(:attr:`workbench.models.Model.overview_figure`).
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
from workbench.plot._base import display_unit, wrap_title
from workbench.plot._continuation import (
    CURVE_COLOURS,
    CURVE_MARKS,
    LABEL_MARKS,
    branch_figure,
    chaos_map_figure,
    curve_figure,
    curve_overlay,
    periodic_end_overlay,
)
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
    "CURVE_COLOURS",
    "CURVE_MARKS",
    "LABEL_MARKS",
    "PANELS_PER_FIGURE",
    "CoarseSamplingWarning",
    "coarse_sampling",
    "display_unit",
    "failure_note",
    "mark_failed",
    "run_phase_figure",
    "run_poincare_figure",
    "run_status_note",
    "wrap_title",
    "bifurcation_figure",
    "branch_figure",
    "campaign_figure",
    "chaos_map_figure",
    "curve_figure",
    "curve_overlay",
    "periodic_end_overlay",
    "embedding_figure",
    "floquet_figure",
    "jacobian_spectrum_figure",
    "lle_figure",
    "phase_figure",
    "poincare_figure",
    "run_figure_names",
    "run_figures",
    "timeseries_figure",
    "verification_figure",
    "work_precision_figure",
    "zero_one_figure",
]
