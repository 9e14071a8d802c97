"""The run layer: the one place where a scene becomes a problem, is integrated, and becomes a
dataset with its provenance.

``prepare(scene)`` builds the model's problem and the record times once; ``integrate`` runs it
with the scene's solver settings; ``derive`` and ``to_dataset`` label the result;
``simulate(scene)`` does all of it. Everything that runs a scene (campaign blocks, accuracy,
Benettin's exponent, verification, studies) goes through these functions.

>>> from workbench.run import prepare, integrate
>>> p = prepare({"model": {"name": "duffing"}, "run": {"cycles": 1}})
>>> integrate(p).status.label
'ok'
"""

from workbench.run._compare import divergence_time, separation, short_scene, with_solver
from workbench.run._dataset import (
    TIME_ATTRS,
    derive,
    provenance,
    results_digest,
    run_status,
    status_attrs,
    to_dataset,
)
from workbench.run._ensemble import (
    DEFAULT_PERTURBATION,
    REALISATION_ATTRS,
    perturb_initial_state,
    scene_perturbation,
)
from workbench.run._memory import (
    MEMORY_ENV,
    MemoryLimitError,
    check_memory,
    format_bytes,
    memory_limit,
    parse_bytes,
    record_count,
    values_per_record,
    what_to_lower,
)
from workbench.run._parameters import PARAMETERS_ATTR, parameter_coords
from workbench.run._prepare import Prepared, forcing_period, prepare, record_times
from workbench.run._simulate import check_error, integrate, simulate

__all__ = [
    "DEFAULT_PERTURBATION",
    "MEMORY_ENV",
    "MemoryLimitError",
    "PARAMETERS_ATTR",
    "REALISATION_ATTRS",
    "TIME_ATTRS",
    "Prepared",
    "check_error",
    "check_memory",
    "forcing_period",
    "format_bytes",
    "memory_limit",
    "parse_bytes",
    "record_count",
    "values_per_record",
    "what_to_lower",
    "perturb_initial_state",
    "scene_perturbation",
    "derive",
    "divergence_time",
    "integrate",
    "parameter_coords",
    "prepare",
    "provenance",
    "record_times",
    "results_digest",
    "run_status",
    "separation",
    "short_scene",
    "simulate",
    "status_attrs",
    "to_dataset",
    "with_solver",
]
