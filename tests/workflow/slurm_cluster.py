"""A throwaway one-node SLURM cluster (munge + slurmctld + slurmd) for tests and CI.

Everything lives in one private temporary folder: a fresh munge key and socket, slurm.conf,
state, spool, logs; ports are picked free. A system munge or SLURM, if any, is left alone.
Client commands find the cluster through ``SLURM_CONF`` (see ``SlurmCluster.env``). Jobs
cannot rely on it: Snakemake's slurm-jobstep executor drops every ``SLURM_*`` variable
(SLURM_CONF included) before its inner ``srun``, which then looks for the compiled-in
/etc/slurm/slurm.conf. So slurmd runs in a private mount namespace in which our folder is
bind-mounted on /etc/slurm; its jobs inherit that view, nothing else sees it. Where a
mount namespace cannot be made, /etc/slurm/slurm.conf is written if absent and removed by
``stop()``.

Recipe: ``SlurmUser=root``, ``proctrack/linuxproc``, ``task/none``,
``select/cons_tres``, no accounting, one node, one default partition; ``slurmctld -D`` and
``slurmd -D`` detached, wait until ``sinfo`` shows the node idle, stop them by pid.

From Python::

    reason = ensure_installed()          # None, or why a cluster cannot be had here
    with SlurmCluster.start() as c:      # stopped on exit, also after an error
        subprocess.run(["srun", "hostname"], env=c.env)

From a shell (CI)::

    python tests/workflow/slurm_cluster.py install   # apt-get the packages if missing
    python tests/workflow/slurm_cluster.py check     # start, run one job, stop
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

APT_PACKAGES = ("slurm-wlm", "munge")  # slurm-wlm = slurmctld + slurmd + slurm-client
BINARIES = ("munged", "slurmctld", "slurmd", "sbatch", "srun", "squeue", "sinfo", "scancel")


def missing_binaries() -> list[str]:
    return [b for b in BINARIES if _which(b) is None]


def _which(name: str) -> str | None:
    # The daemons live in /usr/sbin, which a non-login PATH may lack.
    path = os.environ.get("PATH", "") + os.pathsep + "/usr/sbin" + os.pathsep + "/sbin"
    return shutil.which(name, path=path)


def ensure_installed(timeout: float = 900.0) -> str | None:
    """Install the Debian packages if a binary is missing; None when all are there, else
    the reason they cannot be had (not root, no apt-get, apt-get failed)."""
    missing = missing_binaries()
    if not missing:
        return None
    if os.geteuid() != 0:
        return f"SLURM/munge binaries missing ({', '.join(missing)}) and not root to apt-get them"
    if shutil.which("apt-get") is None:
        return f"SLURM/munge binaries missing ({', '.join(missing)}) and no apt-get here"
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    for cmd in (
        ["apt-get", "update", "-qq"],
        ["apt-get", "install", "-y", "-qq", "--no-install-recommends", *APT_PACKAGES],
    ):
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout)
        except subprocess.TimeoutExpired:
            return f"`{' '.join(cmd)}` took more than {timeout:.0f} s"
        if r.returncode != 0:
            return f"`{' '.join(cmd)}` failed ({r.returncode}): {(r.stderr or r.stdout)[-500:]}"
    missing = missing_binaries()
    if missing:
        return f"still missing after apt-get install {' '.join(APT_PACKAGES)}: {missing}"
    return None


SYSTEM_CONF = Path("/etc/slurm/slurm.conf")  # Debian's compiled-in default


def _can_bind_mount() -> bool:
    """Whether a private mount namespace with a bind mount on /etc/slurm can be made."""
    if shutil.which("unshare") is None or not SYSTEM_CONF.parent.is_dir():
        return False
    probe = ["unshare", "--mount", "--propagation", "private", "sh", "-c",
             "mount --bind /tmp /etc/slurm"]  # fmt: skip
    try:
        return subprocess.run(probe, capture_output=True, timeout=30).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _node_hardware() -> dict[str, str]:
    """What ``slurmd -C`` detects (CPUs, Sockets..., RealMemory [MB]) as key -> value."""
    r = subprocess.run([_which("slurmd") or "slurmd", "-C"], capture_output=True, text=True,
                       timeout=60, check=True)  # fmt: skip
    first = r.stdout.splitlines()[0]
    return dict(kv.split("=", 1) for kv in first.split() if "=" in kv)


SLURM_CONF = """\
# one-node test cluster, written by tests/workflow/slurm_cluster.py
ClusterName=hugomaptest
SlurmctldHost={node}(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={munge_socket}
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
# finished jobs stay visible to squeue this long: the executor's status polling needs it,
# and test_slurm reads every job of the sweep at its end (with 300 s a sweep slowed by a
# loaded machine lost its first jobs from the list)
MinJobAge=3600
ReturnToService=2
KillWait=5
StateSaveLocation={root}/state
SlurmdSpoolDir={root}/spool
SlurmctldPidFile={root}/slurmctld.pid
SlurmdPidFile={root}/slurmd.pid
SlurmctldLogFile={root}/slurmctld.log
SlurmdLogFile={root}/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
NodeName={node} NodeAddr=127.0.0.1 CPUs={cpus} Boards={boards} SocketsPerBoard={sockets} \
CoresPerSocket={cores} ThreadsPerCore={threads} RealMemory={mem_mb} State=UNKNOWN
PartitionName=main Nodes={node} Default=YES MaxTime=INFINITE State=UP
"""


class SlurmCluster:
    """munged, slurmctld and slurmd started by this object, stopped by ``stop()``."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.conf = root / "etc" / "slurm.conf"  # root/etc is what jobs see as /etc/slurm
        self.system_conf: Path | None = None  # /etc/slurm/slurm.conf, if we had to write it
        self.node = socket.gethostname().split(".")[0]
        self.procs: dict[str, subprocess.Popen] = {}
        self.env: dict[str, str] = dict(os.environ, SLURM_CONF=str(self.conf))
        self.env["PATH"] = self.env.get("PATH", "") + os.pathsep + "/usr/sbin"

    @classmethod
    def start(cls, timeout: float = 60.0, mem_fraction: float = 0.8) -> SlurmCluster:
        """Start the three daemons and wait until the node is idle; on any failure stop
        what was started and raise RuntimeError with the daemons' log tails."""
        root = Path(tempfile.mkdtemp(prefix="hugomap-slurm-"))
        # munged wants every folder above its socket searchable by all (pytest's tmp_path
        # base is 0700, hence a folder of our own in the system temp dir).
        root.chmod(0o755)
        cluster = cls(root)
        try:
            cluster._start(timeout, mem_fraction)
        except BaseException:
            cluster.stop()
            raise
        return cluster

    def _start(self, timeout: float, mem_fraction: float) -> None:
        root = self.root
        for d in ("state", "spool", "munge", "etc"):
            (root / d).mkdir()
        key = root / "munge" / "munge.key"
        key.write_bytes(os.urandom(128))  # what `mungekey -c` makes: 1024 random bits
        key.chmod(0o600)
        sock = root / "munge.sock"
        self._spawn("munged", [_which("munged") or "munged", "-F", f"--socket={sock}",
                               f"--key-file={key}", f"--pid-file={root}/munge/munged.pid",
                               f"--seed-file={root}/munge/munged.seed",
                               f"--log-file={root}/munged.log"])  # fmt: skip
        self._wait(lambda: sock.exists(), timeout, "munged socket")

        hw = _node_hardware()
        self.conf.write_text(
            SLURM_CONF.format(
                node=self.node, root=root, munge_socket=sock,
                ctld_port=_free_port(), slurmd_port=_free_port(),
                cpus=hw.get("CPUs", os.cpu_count() or 1), boards=hw.get("Boards", 1),
                sockets=hw.get("SocketsPerBoard", 1),
                cores=hw.get("CoresPerSocket", os.cpu_count() or 1),
                threads=hw.get("ThreadsPerCore", 1),
                mem_mb=int(int(hw.get("RealMemory", 2048)) * mem_fraction),
            )
        )  # fmt: skip
        self._spawn("slurmctld", [_which("slurmctld") or "slurmctld", "-D", "-i",
                                  "-f", str(self.conf)])  # fmt: skip
        slurmd = [_which("slurmd") or "slurmd", "-D", "-N", self.node, "-f", str(self.conf)]
        if _can_bind_mount():
            slurmd = ["unshare", "--mount", "--propagation", "private", "sh", "-c",
                      'mount --bind "$0" /etc/slurm && exec "$@"', str(self.conf.parent),
                      *slurmd]  # fmt: skip
        elif not SYSTEM_CONF.exists():
            SYSTEM_CONF.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(self.conf, SYSTEM_CONF)
            self.system_conf = SYSTEM_CONF
        else:
            raise RuntimeError(
                f"jobs would read {SYSTEM_CONF} (the slurm-jobstep executor drops SLURM_CONF):"
                " no mount namespace can be made to hide it, and it is not ours to overwrite"
            )
        self._spawn("slurmd", slurmd)
        self._wait(lambda: self.node_state() == "idle", timeout, "the node to become idle")

    def _spawn(self, name: str, cmd: list[str]) -> None:
        # Own session: a Ctrl-C meant for pytest does not hit the daemons first; stop()
        # ends them in order.
        with open(self.root / f"{name}.stdout", "wb") as out:
            self.procs[name] = subprocess.Popen(
                cmd, stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT,
                start_new_session=True, env=self.env,
            )  # fmt: skip

    def _wait(self, ready, timeout: float, what: str) -> None:
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            for name, p in self.procs.items():
                if p.poll() is not None:
                    raise RuntimeError(f"{name} exited ({p.returncode}) while waiting for "
                                       f"{what}\n{self.logs()}")  # fmt: skip
            if ready():
                return
            time.sleep(0.2)
        raise RuntimeError(f"timed out after {timeout:.0f} s waiting for {what}\n{self.logs()}")

    def node_state(self) -> str:
        r = subprocess.run(["sinfo", "-h", "-N", "-o", "%T"], capture_output=True, text=True,
                           env=self.env, timeout=30)  # fmt: skip
        return r.stdout.strip()

    def jobs(self) -> list[dict[str, str]]:
        """All jobs the controller still knows (finished ones for MinJobAge): id, name,
        state, cpus, mem (e.g. '1031M'), time_limit (e.g. '6:00'), comment."""
        fmt = "%i|%j|%T|%C|%m|%l|%k"
        r = subprocess.run(["squeue", "-h", "--states=all", "-o", fmt], capture_output=True,
                           text=True, env=self.env, timeout=30, check=True)  # fmt: skip
        keys = ("id", "name", "state", "cpus", "mem", "time_limit", "comment")
        n = fmt.count("|")
        return [dict(zip(keys, ln.split("|", n), strict=True)) for ln in r.stdout.splitlines()]

    def logs(self, tail: int = 2000) -> str:
        parts = []
        for f in sorted(self.root.glob("*.log")) + sorted(self.root.glob("*.stdout")):
            text = f.read_text(errors="replace")
            if text.strip():
                parts.append(f"--- {f.name} ---\n{text[-tail:]}")
        return "\n".join(parts)

    def running(self) -> list[str]:
        return [name for name, p in self.procs.items() if p.poll() is None]

    def stop(self, timeout: float = 20.0) -> None:
        """Cancel leftover jobs, then SIGTERM slurmd, slurmctld, munged (SIGKILL after
        ``timeout``), each by the pid this object started; remove the folder."""
        if "slurmctld" in self.running():
            with contextlib.suppress(Exception):
                subprocess.run(["scancel", "--full", "--user", str(os.geteuid())],
                               env=self.env, capture_output=True, timeout=30)  # fmt: skip
                t_end = time.monotonic() + timeout
                while time.monotonic() < t_end and any(
                    j["state"] in ("RUNNING", "COMPLETING", "PENDING") for j in self.jobs()
                ):
                    time.sleep(0.5)
        for name in ("slurmd", "slurmctld", "munged"):
            p = self.procs.get(name)
            if p is None or p.poll() is not None:
                continue
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(timeout)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(timeout)
        if self.system_conf is not None:
            self.system_conf.unlink(missing_ok=True)
            self.system_conf = None
        shutil.rmtree(self.root, ignore_errors=True)

    def __enter__(self) -> SlurmCluster:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _check() -> int:
    """Start a cluster, run one batch job through it, stop it; 0 on success."""
    with SlurmCluster.start() as c:
        r = subprocess.run(["sbatch", "--wait", "-o", str(c.root / "job.out"), "--wrap",
                            "srun hostname"], capture_output=True, text=True, env=c.env,
                           timeout=120)  # fmt: skip
        out = (c.root / "job.out").read_text() if (c.root / "job.out").exists() else ""
        print(r.stdout, r.stderr, out, sep="\n")
        ok = r.returncode == 0 and c.node in out
        if not ok:
            print(c.logs(), file=sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    what = sys.argv[1] if len(sys.argv) > 1 else "check"
    if what == "install":
        reason = ensure_installed()
        if reason:
            sys.exit(f"cannot install SLURM: {reason}")
    elif what == "check":
        sys.exit(_check())
    else:
        sys.exit(f"usage: {sys.argv[0]} install|check")
