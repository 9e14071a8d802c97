"""What a store's lock guarantees on the file system it lives on.

A store's lock is ``flock`` on a file in the store directory (:func:`store_lock`). On a local
file system (ext4, xfs, tmpfs, ...) it keeps out every other process of the host, which is every
process that can reach the file. On a shared one it depends on the client's mount options
(read from ``/proc/self/mounts``):

NFS (``nfs``, ``nfs4``)
    Since Linux 2.6.12 the client emulates ``flock`` with a POSIX byte-range lock over the whole
    file, held by the server (NLM for NFSv3, the protocol's own locks for NFSv4): coherent
    across clients (``flock(2)``, "NFS details"). Not with ``local_lock=flock`` or
    ``local_lock=all`` (the lock stays on the client) or ``nolock`` (NFSv3: no server locks at
    all), see ``nfs(5)``. An emulated lock also conflicts with a ``fcntl`` lock on the same file,
    and the lock of a client that died is released only when its lease expires (NFSv4, ~90 s).
Lustre (``lustre``)
    ``-o flock``: coherent across clients; ``-o localflock``: each client node keeps its own
    locks (a process on another node takes the same lock at once); neither (``noflock``):
    ``flock`` fails (ENOSYS) (``mount.lustre(8)``).
CephFS (``ceph``)
    Coherent across clients.
Other network or FUSE file systems (GPFS, BeeGFS, CIFS, sshfs, ...)
    Unknown here: BeeGFS keeps ``flock`` on the client unless its client configuration says
    otherwise (``tuneUseGlobalFileLocks``), CIFS with ``nobrl`` too.

:func:`lock_scope` classifies the file system of a path as ``"host"`` (local), ``"cluster"``
(coherent across nodes), ``"node"`` (node-local on a shared file system: a campaign on another
node writing the same store is not refused), ``"none"`` (``flock`` fails) or ``"unknown"``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

__all__ = ["LockScope", "lock_scope", "mount_of"]

LOCAL = frozenset(
    "ext2 ext3 ext4 xfs btrfs zfs f2fs jfs reiserfs tmpfs ramfs overlay devtmpfs squashfs "
    "apfs hfs hfsplus ufs vfat exfat ntfs ntfs3".split()
)
MOUNTS = "/proc/self/mounts"


@dataclass(frozen=True)
class LockScope:
    """Where a lock on the file system of ``path`` is seen (see the module docstring)."""

    scope: str  # host, cluster, node, none or unknown
    fstype: str
    mountpoint: str
    options: tuple[str, ...]
    reason: str

    @property
    def node_local(self) -> bool:
        """Whether a process on another node could hold the same lock at the same time."""
        return self.scope in ("node", "unknown")


def _unescape(field: str) -> str:
    """A path field of /proc/mounts (octal escapes for space, tab, newline, backslash)."""
    out, i = [], 0
    while i < len(field):
        code = field[i + 1 : i + 4]
        if field[i] == "\\" and len(code) == 3 and code.isdigit():
            out.append(chr(int(field[i + 1 : i + 4], 8)))
            i += 4
        else:
            out.append(field[i])
            i += 1
    return "".join(out)


def mount_of(
    path: str | os.PathLike, mounts: str | None = None
) -> tuple[str, str, tuple[str, ...]]:
    """The mount point, file system type and options of the file system holding ``path``
    (symbolic links resolved), from ``mounts`` (the text of ``/proc/self/mounts``; read when
    None). ``("", "", ())`` where there is no mount table (not Linux)."""
    if mounts is None:
        try:
            mounts = Path(MOUNTS).read_text()
        except OSError:
            return "", "", ()
    target = os.path.realpath(Path(path).expanduser().absolute())
    best = ("", "", ())
    for line in mounts.splitlines():
        fields = line.split()
        if len(fields) < 4:
            continue
        mountpoint = _unescape(fields[1])
        inside = target == mountpoint or target.startswith(mountpoint.rstrip("/") + "/")
        if inside and len(mountpoint) >= len(best[0]):  # the last, deepest mount wins
            best = (mountpoint, fields[2], tuple(fields[3].split(",")))
    return best


def lock_scope(path: str | os.PathLike, mounts: str | None = None) -> LockScope:
    """What ``flock`` on a file at ``path`` excludes, from the mount table (see the module
    docstring); ``mounts`` is the text of ``/proc/self/mounts`` (read when None).

    >>> table = "srv:/export /data nfs4 rw,vers=4.2,local_lock=none 0 0\\n"
    >>> lock_scope("/data/sweep.nc", table).scope
    'cluster'
    >>> lock_scope("/data/sweep.nc", table.replace("local_lock=none", "local_lock=all")).scope
    'node'
    """
    mountpoint, fstype, options = mount_of(path, mounts)
    opts = set(options)
    kind = fstype.split(".")[0]
    if not fstype:
        return LockScope("unknown", "", "", (), "no mount table to read")
    if fstype in LOCAL:
        return LockScope("host", fstype, mountpoint, options, "a local file system")
    if kind in ("nfs", "nfs4"):
        local = {o.split("=", 1)[1] for o in opts if o.startswith("local_lock=")}
        if "nolock" in opts:
            why = "NFS mounted with nolock: locks stay on this client"
            return LockScope("node", fstype, mountpoint, options, why)
        if local & {"flock", "all"}:
            why = f"NFS mounted with local_lock={local.pop()}: flock stays on this client"
            return LockScope("node", fstype, mountpoint, options, why)
        why = "NFS emulates flock with a byte-range lock held by the server"
        return LockScope("cluster", fstype, mountpoint, options, why)
    if kind == "lustre":
        if "flock" in opts:
            why = "Lustre mounted with flock: coherent across clients"
            return LockScope("cluster", fstype, mountpoint, options, why)
        if "localflock" in opts:
            why = "Lustre mounted with localflock: each node keeps its own locks"
            return LockScope("node", fstype, mountpoint, options, why)
        why = "Lustre mounted without flock or localflock (noflock): flock fails"
        return LockScope("none", fstype, mountpoint, options, why)
    if kind == "ceph":
        return LockScope("cluster", fstype, mountpoint, options, "CephFS: coherent flock")
    why = f"a {fstype} file system, whose flock may or may not reach other nodes"
    return LockScope("unknown", fstype, mountpoint, options, why)
