"""The paper's studies (Chen et al.): scenes under ``studies/``, run, measured, compared.

>>> from workbench.study import available_studies
>>> "friction_models" in available_studies()
True

``workbench study NAME`` (or ``all``) runs a study; ``workbench study report`` writes
``studies/REPORT.md`` from the stored summaries; ``make studies`` does both for every study.
The scenes ship with the package (``workbench/study/scenes``, in the repository a link to
``studies/``), so an installed wheel runs the studies too; it writes the report beside the
summaries (:func:`report_path`).
"""

from workbench.study._report import write_report
from workbench.study._run import run_study
from workbench.study._spec import Study, available_studies, load_study, quick_scene, report_path

__all__ = [
    "Study",
    "available_studies",
    "load_study",
    "quick_scene",
    "report_path",
    "run_study",
    "write_report",
]
