"""netCDF archives of runs and campaigns: atomic writing (a temporary file, then a rename that
never replaces a file unless asked to and never a device; a full disk or any other failed write
in one line naming the path; no stale temporaries), exact reading, output paths checked before
any work, the integrity of stores (one writer at a time, checksummed files), and the archive
format (``format_version`` on every archive; older formats upgraded or refused with a
message)."""

from workbench.archive._atomic import (
    DiskFull,
    OutputExists,
    WriteFailed,
    atomic_path,
    keep_elsewhere,
    remove_stale_temporaries,
    save_figure,
    write_text_atomic,
)
from workbench.archive._format import (
    RECORD_DIM,
    RECORD_TIME,
    SERIES_DIMS,
    stamp_format,
    status_flags,
    upgrade_archive,
)
from workbench.archive._integrity import (
    ArchiveError,
    StoreLocked,
    StoreWarning,
    file_problem,
    mapping_diff,
    read_manifest,
    sha256_file,
    store_lock,
)
from workbench.archive._netcdf import open_run, save_run
from workbench.archive._outputs import check_output_directory, check_output_file

__all__ = [
    "RECORD_DIM",
    "RECORD_TIME",
    "SERIES_DIMS",
    "ArchiveError",
    "DiskFull",
    "OutputExists",
    "StoreLocked",
    "StoreWarning",
    "WriteFailed",
    "atomic_path",
    "check_output_directory",
    "check_output_file",
    "file_problem",
    "keep_elsewhere",
    "mapping_diff",
    "open_run",
    "read_manifest",
    "remove_stale_temporaries",
    "save_figure",
    "save_run",
    "sha256_file",
    "stamp_format",
    "status_flags",
    "store_lock",
    "upgrade_archive",
    "write_text_atomic",
]
