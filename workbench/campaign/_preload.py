"""Imported by the fork server of a local campaign pool: load the campaign's compiled kernel once.

The client puts the scene of the campaign's first point (TOML) in the environment variable
``WORKBENCH_CAMPAIGN_PRELOAD`` (and the module of a user's model, which the server imports
first, in ``WORKBENCH_CAMPAIGN_MODEL``) before the fork server starts; importing this module
there loads (or, on a cold cache, compiles) the model's kernel a single time, and every worker
forked from the server inherits the machine code instead of loading it from disk itself (and
xarray's and netCDF's first-use imports, and the package versions of the provenance). Anything
that goes wrong here is ignored: the workers then load the kernel on their first point as usual.
(A dask cluster's workers get the same through a worker plugin: ``_cluster``.)

First of all the server arms its lifeline (``_lifeline``): it dies with the campaign that
started it (the pid in ``WORKBENCH_CAMPAIGN_PID``), and its workers die with it.
"""

from __future__ import annotations

import json
import os

from workbench.campaign._block import MODEL_ENV, PRELOAD_ENV
from workbench.campaign._lifeline import PARENT_ENV, die_with_parent
from workbench.campaign._warm import load_kernel, warm_io

if os.environ.get(PARENT_ENV):
    die_with_parent(int(os.environ[PARENT_ENV]))
if os.environ.get(PRELOAD_ENV):
    try:
        warm_io()
        load_kernel(os.environ[PRELOAD_ENV], *json.loads(os.environ.get(MODEL_ENV, '["", ""]')))
    except Exception:  # pragma: no cover - any error: the fork server must start (its workers
        # fork from it); the first block loads the kernel itself and reports a real error
        pass
