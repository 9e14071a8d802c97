"""netCDF archives of runs and campaigns: atomic writing (a temporary file, then a rename) and
exact reading."""

from workbench.archive._netcdf import atomic_path, open_run, save_run, write_text_atomic

__all__ = ["atomic_path", "open_run", "save_run", "write_text_atomic"]
