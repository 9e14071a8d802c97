"""What a store's lock guarantees where the store lives: the mount table read, and the checks
on file systems whose locks other nodes do not see (NFS local_lock, Lustre localflock)."""

import errno
import json
import socket

import pytest

from workbench.archive import ArchiveError, StoreLocked, StoreWarning, _integrity, store_lock
from workbench.archive._filesystem import LockScope, lock_scope, mount_of

TABLE = """\
/dev/vda / ext4 rw,relatime 0 0
tmpfs /tmp tmpfs rw,nosuid 0 0
srv:/export/home /home nfs4 rw,vers=4.2,hard,proto=tcp,local_lock=none,addr=10.0.0.1 0 0
srv:/old /old nfs rw,vers=3,nolock,local_lock=all 0 0
srv:/samba /samba nfs4 rw,vers=4.1,local_lock=flock 0 0
10.0.0.2@o2ib:/scratch /scratch lustre rw,flock,lazystatfs 0 0
10.0.0.2@o2ib:/work /lustre/work lustre rw,localflock,lazystatfs 0 0
10.0.0.2@o2ib:/plain /lustre/plain lustre rw,lazystatfs 0 0
beegfs_nodev /beegfs beegfs rw,relatime,cfgFile=/etc/beegfs/beegfs-client.conf 0 0
mon1:6789:/ /ceph ceph rw,name=admin 0 0
srv:/export/home/me/deep /home/me/deep\\040dir nfs4 rw,vers=4.2,local_lock=all 0 0
"""


@pytest.mark.parametrize(
    ("path", "scope", "fstype"),
    [
        ("/data/sweep.nc", "host", "ext4"),
        ("/tmp/x/sweep.nc", "host", "tmpfs"),
        ("/home/me/sweep.nc", "cluster", "nfs4"),  # flock emulated by a server-held lock
        ("/old/sweep.nc", "node", "nfs"),  # nolock: NFSv3 without the lock manager
        ("/samba/sweep.nc", "node", "nfs4"),  # local_lock=flock
        ("/scratch/sweep.nc", "cluster", "lustre"),  # -o flock
        ("/lustre/work/sweep.nc", "node", "lustre"),  # -o localflock
        ("/lustre/plain/sweep.nc", "none", "lustre"),  # neither: flock fails
        ("/beegfs/sweep.nc", "unknown", "beegfs"),
        ("/ceph/sweep.nc", "cluster", "ceph"),
        ("/home/me/deep dir/sweep.nc", "node", "nfs4"),  # the deepest mount, unescaped
    ],
)
def test_the_lock_scope_of_a_path_comes_from_its_mount(path, scope, fstype):
    s = lock_scope(path, TABLE)
    assert (s.scope, s.fstype) == (scope, fstype), s
    assert s.node_local == (scope in ("node", "unknown"))


def test_this_machines_temporary_directory_is_read(tmp_path):
    mountpoint, fstype, options = mount_of(tmp_path)
    assert fstype and options and str(tmp_path).startswith(mountpoint)


NODE = LockScope("node", "lustre", "/lustre/work", ("rw", "localflock"), "localflock")


def test_a_node_local_lock_warns_and_refuses_a_holder_on_another_host(tmp_path, monkeypatch):
    monkeypatch.setattr(_integrity, "lock_scope", lambda directory: NODE)
    store = tmp_path / "s.blocks"
    with pytest.warns(StoreWarning, match="other processes on this node only"):
        with store_lock(store, "campaign store 'x'"):
            pass
    # a lock file written by a campaign on another node, whose lock this node cannot see
    store.mkdir(exist_ok=True)
    other = {"pid": 4242, "host": "node-17", "started": "2026-01-01T00:00:00+00:00"}
    (store / "lock").write_text(json.dumps(other) + "\n")
    with pytest.raises(StoreLocked, match=r"node-17.*may still be writing it.*delete the lock"):
        with store_lock(store, "campaign store 'x'"):
            pass
    # left by this host: the kernel dropped its lock, so it is stale and taken over
    (store / "lock").write_text(json.dumps({**other, "host": socket.gethostname()}) + "\n")
    with pytest.warns(StoreWarning, match="took over the lock"):
        with store_lock(store, "campaign store 'x'") as stale:
            assert stale["pid"] == 4242


def test_a_coherent_lock_takes_over_a_lock_file_of_another_host(tmp_path, monkeypatch):
    cluster = LockScope("cluster", "nfs4", "/home", ("rw",), "NFS")
    monkeypatch.setattr(_integrity, "lock_scope", lambda directory: cluster)
    store = tmp_path / "s.blocks"
    store.mkdir()
    other = {"pid": 4242, "host": "node-17"}
    (store / "lock").write_text(json.dumps(other) + "\n")
    with pytest.warns(StoreWarning, match="took over the lock"):  # its holder died
        with store_lock(store, "campaign store 'x'"):
            pass


def test_a_file_system_without_flock_is_named(tmp_path, monkeypatch):
    import fcntl

    def no_flock(fd, op):
        raise OSError(errno.ENOSYS, "Function not implemented")

    monkeypatch.setattr(fcntl, "flock", no_flock)
    none = LockScope("none", "lustre", "/lustre/plain", ("rw",), "Lustre mounted without flock")
    monkeypatch.setattr(_integrity, "lock_scope", lambda directory: none)
    with pytest.raises(ArchiveError, match=r"flock .* fails .*without flock.*-o flock"):
        with store_lock(tmp_path / "s.blocks", "campaign store 'x'"):
            pass
