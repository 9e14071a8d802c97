"""Shared fixtures. Numba compiles once per model into the on-disk cache (see workbench._cache)."""

import matplotlib

matplotlib.use("Agg")
