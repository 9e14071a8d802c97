"""The version of workbench and of the archives it writes, and the rule that moves them.

``__version__`` (also the ``version`` of pyproject.toml; ``tests/package/test_version.py`` holds
them
equal) is ``0.MINOR.PATCH`` while the package is young: MINOR goes up when the archive format
or the results change (a scene gives other numbers than rounding explains: a default, a model,
a solver, an estimator), PATCH for any other release (documentation, speed at identical
results, new functions). ``CHANGELOG.md`` says what each version changed.

``FORMAT_VERSION`` is stamped on every archive workbench writes (the global attribute
``format_version``: runs, campaigns and their blocks, work-precision studies, study summaries,
verifications). It goes up when a reader of the previous format would misread the new
archives: a variable, dimension, attribute or flag value renamed, removed or given another
meaning. Adding a variable or an attribute does not move it. Reading an archive of an older
format upgrades it where the change is known and unambiguous, and refuses it with a message
that says what to do where it is not (:mod:`workbench.archive`); a newer format is refused.

Formats: 1, workbench 0.1.0 (no ``format_version`` attribute; statuses ``done``,
``solver_failed``, ``terminated_early``); 2, workbench 0.2.0 (one status vocabulary:
:class:`workbench.Status`); 3, workbench 0.6.0 (the simulated time stored as a CF 1.11 time
coordinate: :mod:`workbench.archive._format`); 4, workbench 0.6.0 (a campaign whose points
have their own record times runs along ``record``, not ``time``: :mod:`workbench.archive._format`).
"""

__all__ = ["FORMAT_VERSION", "__version__"]

__version__ = "0.6.0"
FORMAT_VERSION = 4
