"""A closed cluster (issue 37, finding 1): every dask scheduler workbench starts speaks TLS with
credentials made for it, listens on the loopback or on the interface the user names, never on
every interface, and refuses a client without its credentials; a campaign runs on it. The local
pool listens on no network at all."""

from __future__ import annotations

import contextlib
import gc
import ipaddress
import os
import socket
import stat
import threading
import time
from pathlib import Path

import pytest
from _scenes import DUFFING_SWEEP as SCENE

import workbench
from workbench.campaign import jobqueue_cluster, local_cluster
from workbench.campaign._jobqueue import cluster_security, dashboard_options

distributed = pytest.importorskip("distributed")
pytest.importorskip("cryptography")
psutil = pytest.importorskip("psutil")


def _listening(procs) -> set[tuple[str, int]]:
    """The (address, port) of every TCP/UDP socket that ``procs`` listen on."""
    found = set()
    for p in procs:
        with contextlib.suppress(psutil.Error):
            for c in p.net_connections(kind="inet"):
                if c.status == psutil.CONN_LISTEN:
                    found.add((c.laddr.ip, c.laddr.port))
    return found


def _tree() -> list:
    me = psutil.Process()
    return [me, *me.children(recursive=True)]


def _loopback(address: str) -> bool:
    return ipaddress.ip_address(address.split("%")[0]).is_loopback


def _attacker_writes(marker: Path) -> str:
    """What the finding's intruder ran on the scheduler (``run_on_scheduler``)."""
    marker.write_text("intruder")
    return "ran"


def _refused(address: str, marker: Path, **kwargs) -> str:
    """Connect as an intruder and run code on the scheduler; the error if refused."""
    try:
        with distributed.Client(address, timeout=5, **kwargs) as intruder:
            intruder.run_on_scheduler(_attacker_writes, marker)
    except Exception as exc:  # refused: at the handshake, or no TLS context at all
        refusal = f"{type(exc).__name__}: {exc}"
    else:
        return ""
    # the refused client, now: distributed's __del__ of a client that failed to start takes
    # a class-wide lock, and deadlocked the next Client's start when the collector ran it there
    gc.collect()
    return refusal


def _refused_without_certificate(address: str) -> str:
    """Speak TLS to the scheduler without presenting a certificate (and trusting any server's),
    then ask it who it is; the error if refused."""
    import asyncio
    import ssl

    from distributed.comm import connect

    ctx = ssl.create_default_context(ssl.Purpose.SERVER_AUTH)
    ctx.check_hostname = False
    ctx.verify_mode = ssl.CERT_NONE

    async def ask():
        comm = await connect(address, timeout=5, ssl_context=ctx)
        try:
            await comm.write({"op": "identity"})
            return await comm.read()
        finally:
            comm.abort()

    try:
        answer = asyncio.run(ask())
    except Exception as exc:
        return f"{type(exc).__name__}: {exc}"
    assert not answer, answer  # the scheduler answered: it is open
    return ""


def _assert_closed(address: str, tmp_path: Path) -> None:
    """No client without the cluster's credentials gets in (the scheduler at ``address``)."""
    assert address.startswith("tls://"), address
    marker = tmp_path / "intruder-was-here"
    intruders = {
        "plain TCP, no credentials": (address.replace("tls://", "tcp://", 1), {}),
        "TLS without credentials": (address, {}),
        "TLS with credentials of its own": (
            address,
            {"security": distributed.Security.temporary()},
        ),
    }
    for who, (addr, kwargs) in intruders.items():
        assert _refused(addr, marker, **kwargs), f"{who} got into the scheduler"
    assert not marker.exists()
    assert _refused_without_certificate(address), "a TLS client without a certificate got in"


@pytest.mark.timeout(120)
def test_a_local_cluster_refuses_clients_without_its_credentials(tmp_path):
    before = _listening(_tree())
    with local_cluster(0, dashboard=None) as cluster:
        opened = _listening(_tree()) - before  # the scheduler, its HTTP server (metrics)
        assert len(opened) == 2 and all(_loopback(ip) for ip, _ in opened), opened
        _assert_closed(cluster.scheduler_address, tmp_path)
        marker = tmp_path / "client"
        with distributed.Client(cluster, timeout=30) as client:  # the cluster's own credentials
            assert client.run_on_scheduler(_attacker_writes, marker) == "ran"
        assert marker.read_text() == "intruder"


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_a_campaign_runs_on_a_local_cluster_that_listens_on_the_loopback_only(tmp_path):
    scene = workbench.load_scene(SCENE)
    workbench.simulate(scene.with_parameters(gamma=0.3))  # the kernel in the cache
    before = _listening(_tree())
    with (
        local_cluster(1) as cluster,
        distributed.Client(cluster, timeout=60) as client,
    ):
        ds = workbench.run_campaign(scene, tmp_path / "sweep.nc", client=client)
        assert cluster.scheduler_address.startswith("tls://127.0.0.1:")
        assert cluster.dashboard_link.startswith("http://127.0.0.1:")
        opened = _listening(_tree()) - before  # scheduler, dashboard, nanny, worker
        workers = client.run(os.getpid)
    assert int(ds.status.sum()) == 0 and ds.sizes["gamma"] == 2
    assert len(workers) == 1 and len(opened) >= 4, opened
    assert all(_loopback(ip) for ip, _ in opened), opened


@pytest.mark.slow
@pytest.mark.timeout(300)
def test_the_local_pool_listens_on_no_network(tmp_path):
    """``run_campaign`` without a client: a fork server and its workers, which speak through
    pipes and a Unix socket in a folder of the user's alone: no TCP or UDP port at all."""
    scene = workbench.load_scene(
        {**SCENE, "run": {"cycles": 400}, "sweep": {"gamma": [0.3, 0.35, 0.4, 0.45]}}
    )
    workbench.simulate(scene.with_parameters(gamma=0.3).replace(run={"cycles": 1}))
    seen: dict = {"inet": set(), "unix": set(), "children": set()}
    done = threading.Event()

    def watch():
        while not done.is_set():
            procs = _tree()
            seen["children"].update(p.pid for p in procs[1:])
            seen["inet"] |= _listening(procs)
            for p in procs:
                with contextlib.suppress(psutil.Error):
                    seen["unix"].update(c.laddr for c in p.net_connections("unix") if c.laddr)
            time.sleep(0.02)

    before = _listening(_tree())
    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    try:
        ds = workbench.run_campaign(scene, tmp_path / "pool.nc", workers=2, chunk=1)
    finally:
        done.set()
        watcher.join()
    assert int(ds.status.sum()) == 0
    assert len(seen["children"]) >= 2  # the watcher saw the pool's processes
    assert seen["inet"] - before == set()
    for path in seen["unix"]:
        if path.startswith("/"):  # a socket file: in a folder that only its owner enters
            mode = os.stat(os.path.dirname(path)).st_mode
            assert not mode & 0o077, (path, oct(mode))


def _non_loopback_interface() -> tuple[str, str] | None:
    for nic, addresses in psutil.net_if_addrs().items():
        for a in addresses:
            if a.family == socket.AF_INET and not _loopback(a.address):
                return nic, a.address
    return None


def _job_tls_files(script: str) -> dict[str, Path]:
    command = script.strip().splitlines()[-1].split()
    return {
        flag: Path(command[command.index(flag) + 1])
        for flag in ("--tls-ca-file", "--tls-cert", "--tls-key")
    }


@pytest.mark.timeout(120)
@pytest.mark.parametrize("where", ["loopback", "network"])
def test_a_jobqueue_cluster_listens_on_the_named_interface_and_refuses_intruders(tmp_path, where):
    if where == "loopback":
        interface, ip = "lo", "127.0.0.1"
    else:
        found = _non_loopback_interface()
        if found is None:
            pytest.skip("this host has no network interface besides the loopback")
        interface, ip = found
    cache = tmp_path / "cache"
    before = _listening(_tree())
    cluster = jobqueue_cluster("slurm", cores=2, memory="2GB", cache_dir=cache, interface=interface)
    try:
        opened = _listening(_tree()) - before
        script = cluster.job_script()
        assert cluster.scheduler_address.startswith(f"tls://{ip}:")
        # the scheduler on the named interface, its dashboard on the loopback: nothing else
        port = int(cluster.scheduler_address.rsplit(":", 1)[1])
        dashboard = cluster.scheduler_info["services"]["dashboard"]
        assert (ip, port) in opened and ("127.0.0.1", dashboard) in opened, opened
        assert opened <= {(ip, port), ("127.0.0.1", dashboard), ("::1", dashboard)}, opened
        _assert_closed(cluster.scheduler_address, tmp_path)
        # the workers: TLS on the same interface, their own HTTP servers on their loopback
        command = script.strip().splitlines()[-1]
        assert f"dask_worker tls://{ip}:" in command and f"--interface {interface}" in command
        assert "--no-dashboard --dashboard-address 127.0.0.1:0" in command
        # the temporary credentials: files of the user's alone that the job script names
        files = _job_tls_files(script)
        folder = cache / "cluster-credentials"
        assert stat.S_IMODE(folder.stat().st_mode) == 0o700
        for path in files.values():
            assert path.parent == folder and stat.S_IMODE(path.stat().st_mode) == 0o600
        assert "PRIVATE KEY" in files["--tls-key"].read_text()
        assert "PRIVATE KEY" not in script and "BEGIN" not in script
        # those files let a worker in: the credentials a job gets
        worker = distributed.Security(
            tls_ca_file=str(files["--tls-ca-file"]),
            tls_client_cert=str(files["--tls-cert"]),
            tls_client_key=str(files["--tls-key"]),
            require_encryption=True,
        )
        with distributed.Client(cluster.scheduler_address, security=worker, timeout=30) as c:
            assert c.run_on_scheduler(os.getpid) == os.getpid()
    finally:
        cluster.close()


def _write_credentials(folder: Path, key_in_cert: bool = False) -> dict[str, str]:
    """A CA, certificate and key (one self-signed pair) in files, as a user's own would be."""
    made = distributed.Security.temporary()
    folder.mkdir(mode=0o700)
    ca, cert, key = folder / "ca.pem", folder / "cert.pem", folder / "key.pem"
    ca.write_text(made.tls_ca_file)
    cert.write_text(made.tls_worker_cert + (made.tls_worker_key if key_in_cert else ""))
    key.write_text(made.tls_worker_key)
    config = {"distributed.comm.tls.ca-file": str(ca)}
    for role in ("scheduler", "worker", "client"):
        config[f"distributed.comm.tls.{role}.cert"] = str(cert)
        if not key_in_cert:
            config[f"distributed.comm.tls.{role}.key"] = str(key)
    return config


@pytest.mark.timeout(120)
@pytest.mark.parametrize("key_in_cert", [False, True])
def test_the_dask_configs_certificates_are_used_when_named(tmp_path, key_in_cert):
    import dask

    config = _write_credentials(tmp_path / "tls", key_in_cert)
    cert = config["distributed.comm.tls.worker.cert"]
    with dask.config.set(config):
        security = cluster_security()
        assert security.tls_ca_file == config["distributed.comm.tls.ca-file"]
        assert security.tls_worker_key == (cert if key_in_cert else str(tmp_path / "tls/key.pem"))
        cluster = jobqueue_cluster(
            "slurm", cores=1, memory="1GB", cache_dir=tmp_path / "cache", interface="lo"
        )
    try:
        command = cluster.job_script().strip().splitlines()[-1]
        assert f"--tls-cert {cert}" in command and "None" not in command
        assert not (tmp_path / "cache" / "cluster-credentials").exists()  # nothing to write
        _assert_closed(cluster.scheduler_address, tmp_path)  # intruders without the config
        with dask.config.set(config):  # a client that reads it (`workbench campaign --scheduler`)
            with distributed.Client(cluster.scheduler_address, timeout=30) as client:
                assert client.run_on_scheduler(os.getpid) == os.getpid()
    finally:
        cluster.close()


def test_dashboard_addresses():
    assert dashboard_options("localhost:8787") == {
        "dashboard": True,
        "dashboard_address": "localhost:8787",
    }
    # no host: dask would serve it on every interface; here it is the loopback's
    assert dashboard_options(":8787")["dashboard_address"] == "localhost:8787"
    assert dashboard_options("8787")["dashboard_address"] == "localhost:8787"
    assert dashboard_options("0.0.0.0:8787")["dashboard_address"] == "0.0.0.0:8787"  # written
    assert dashboard_options(None) == {"dashboard": False, "dashboard_address": "127.0.0.1:0"}
    for bad in (True, 8787, "", "localhost:port"):
        with pytest.raises(ValueError, match=r"dashboard=.* (must be an|is not an) address"):
            dashboard_options(bad)


def test_security_without_certificates_is_refused():
    with pytest.raises(ValueError, match=r"^security= lacks tls_ca_file, tls_scheduler_cert"):
        cluster_security(distributed.Security())
    with pytest.raises(ValueError, match=r"security='x' must be a distributed.Security"):
        cluster_security("x")
    made = distributed.Security.temporary()
    made.tls_worker_cert = None
    with pytest.raises(ValueError, match=r"^security= lacks tls_worker_cert: "):
        cluster_security(made)


def test_a_dask_config_naming_a_ca_but_not_every_certificate_is_refused(tmp_path):
    import dask

    config = _write_credentials(tmp_path / "tls")
    del config["distributed.comm.tls.client.cert"]
    with (
        dask.config.set(config),
        pytest.raises(
            ValueError,
            match=r"^the dask config lacks distributed.comm.tls.client.cert: a cluster's",
        ),
    ):
        cluster_security()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"interface": None}, r"^jobqueue_cluster needs interface=, .* \(here: lo 127.0.0.1"),
        ({"interface": "no-such-nic"}, r"^interface='no-such-nic' is not a network interface"),
        (
            {"scheduler_options": {"interface": "no-such-nic"}},
            r"^scheduler_options interface='no-such-nic' is not a network interface",
        ),
        (
            {"scheduler_options": {"dashboard_address": ":8787"}},
            r"^scheduler_options dashboard_address=':8787' has no host",
        ),
        ({"protocol": "tcp://"}, r"^protocol='tcp://': a workbench cluster speaks TLS only"),
        ({"security": "x"}, r"^security='x' must be a distributed.Security"),
    ],
)
def test_jobqueue_cluster_refuses_an_open_setup_in_one_line(tmp_path, kwargs, match):
    args = {"cores": 1, "memory": "1GB", "cache_dir": tmp_path / "cache", "interface": "lo"}
    with pytest.raises(ValueError, match=match) as info:
        jobqueue_cluster("slurm", **{**args, **kwargs})
    assert "\n" not in str(info.value)


def test_a_credentials_folder_that_others_may_write_is_refused(tmp_path):
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    with pytest.raises(
        ValueError, match=r"shared_temp_directory='.*shared' \(mode 777, .*chmod go-w"
    ):
        jobqueue_cluster(
            "slurm",
            cores=1,
            memory="1GB",
            cache_dir=tmp_path / "cache",
            interface="lo",
            shared_temp_directory=str(shared),
        )
    assert not list(shared.iterdir())  # no key written there


def test_local_cluster_refuses_plain_tcp():
    with pytest.raises(ValueError, match=r"^protocol='tcp': a workbench cluster speaks TLS"):
        local_cluster(0, protocol="tcp")
