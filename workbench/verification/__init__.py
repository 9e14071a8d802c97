"""Independent verification against the exudyn multibody engine (optional extra ``verify``).

>>> from workbench.verification import verify                                 # doctest: +SKIP
>>> ds = verify("studies/ninebar.toml", horizon=0.02, steps=(2e-6,))    # doctest: +SKIP
"""

from workbench.verification._compare import STATISTICS, verify
from workbench.verification._exudyn import run_exudyn
from workbench.verification._mechanisms import verifiable_models

__all__ = ["STATISTICS", "run_exudyn", "verifiable_models", "verify"]
