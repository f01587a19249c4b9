"""A one-node Slurm cluster on loopback for the cluster tests: munged, slurmctld and
slurmd (Debian's packages slurmctld, slurmd, slurm-client and munge, which
``python3 bootstrap.py test`` installs when run as root) started from a generated
slurm.conf in a temporary directory, and stopped after.

The configuration asks nothing of the machine: process tracking by the process tree
(proctrack/linuxproc), no task plugin and no cgroups, no accounting, one node of 2 CPUs
at 127.0.0.1 (its CPU and memory counts taken from the file: config_overrides), free
ports, and the state, spool, logs and munge socket in the temporary directory. Clients
(sbatch, squeue, scancel; dask-jobqueue calls them) find it through SLURM_CONF."""
from __future__ import annotations

import os
import shutil
import socket
import subprocess
import time
from pathlib import Path

#: the Debian packages, and the commands the cluster needs of them
PACKAGES = ("slurmctld", "slurmd", "slurm-client", "munge")
COMMANDS = ("munged", "slurmctld", "slurmd", "sbatch", "squeue", "scancel", "sinfo")


def which(command: str) -> str | None:
    """The path of ``command`` (daemons live in /usr/sbin, not on every user's PATH)."""
    return shutil.which(command) or shutil.which(command, path="/usr/sbin:/sbin")


def missing() -> str | None:
    """Why a Slurm cluster cannot be started here, or None when it can."""
    absent = [c for c in COMMANDS if which(c) is None]
    if absent:
        return (f"Slurm is not installed ({', '.join(absent)} not found): `python3 bootstrap.py test` installs it "
                f"when run as root, or run `apt-get install {' '.join(PACKAGES)}`")
    if os.geteuid() != 0:
        return "the one-node Slurm of the tests runs its daemons as root (slurmd starts jobs as their user)"
    return None


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Slurm:
    """munged, slurmctld and slurmd in ``root`` (a temporary directory): ``start()``
    waits until the node is idle, ``stop()`` cancels the jobs left and ends the daemons
    (the processes this object started, by their pid). ``env``: what a client needs
    (SLURM_CONF)."""

    NODE = "cracklab1"
    CPUS = 2

    def __init__(self, root):
        self.root = Path(root)
        self.procs: list[subprocess.Popen] = []
        self.conf = self.root / "slurm.conf"
        self.env = {"SLURM_CONF": str(self.conf)}

    # ------------------------------------------------------------------ set-up
    def _write(self):
        for d in ("munge", "state", "spool", "log"):
            (self.root / d).mkdir(parents=True, exist_ok=True)
        (self.root / "munge").chmod(0o711)
        key = self.root / "munge" / "munge.key"
        key.write_bytes(os.urandom(1024))
        key.chmod(0o600)
        host = socket.gethostname().split(".")[0]
        memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") // 2**20
        r = self.root
        self.conf.write_text(f"""\
ClusterName=cracklabtest
SlurmctldHost={host}(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort={free_port()}
SlurmdPort={free_port()}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={r}/munge/munge.socket
StateSaveLocation={r}/state
SlurmdSpoolDir={r}/spool
SlurmctldPidFile={r}/slurmctld.pid
SlurmdPidFile={r}/slurmd.pid
SlurmctldLogFile={r}/log/slurmctld.log
SlurmdLogFile={r}/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
MailProg=/bin/true
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SlurmdParameters=config_overrides
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=30
KillWait=5
NodeName={self.NODE} NodeHostname={host} NodeAddr=127.0.0.1 CPUs={self.CPUS} RealMemory={memory} State=UNKNOWN
PartitionName=test Nodes={self.NODE} Default=YES MaxTime=INFINITE State=UP
""")

    def _spawn(self, name, args):
        out = open(self.root / "log" / f"{name}.out", "wb")
        proc = subprocess.Popen([which(args[0]), *args[1:]], stdin=subprocess.DEVNULL, stdout=out,
                                stderr=subprocess.STDOUT, env={**os.environ, **self.env}, cwd=self.root)
        out.close()
        self.procs.append(proc)
        return proc

    def run(self, *args, check=True, timeout=30) -> str:
        """A client command (sinfo, squeue, scancel, sbatch) against this cluster; its stdout."""
        res = subprocess.run([which(args[0]), *args[1:]], capture_output=True, text=True, timeout=timeout,
                             env={**os.environ, **self.env}, stdin=subprocess.DEVNULL)
        if check and res.returncode != 0:
            raise RuntimeError(f"{' '.join(args)} failed ({res.returncode}): {res.stderr.strip()}")
        return res.stdout

    def log(self, name: str) -> str:
        """The end of a daemon's log (munged.out, slurmctld.log, slurmd.log ...), for messages."""
        path = self.root / "log" / name
        return path.read_text(errors="replace")[-3000:] if path.exists() else f"(no {name})"

    def start(self, timeout: float = 60.0) -> "Slurm":
        self._write()
        m = self.root / "munge"
        self._spawn("munged.out", ["munged", "--foreground", "--force", f"--socket={m}/munge.socket",
                                   f"--key-file={m}/munge.key", f"--pid-file={m}/munged.pid",
                                   f"--seed-file={m}/munged.seed", f"--log-file={self.root}/log/munged.log"])
        try:
            self._wait(lambda: (m / "munge.socket").exists(), 10, "munged.out", "munged made no socket")
            self._spawn("slurmctld.out", ["slurmctld", "-D", "-i"])
            self._wait(lambda: self.run("sinfo", "-h", check=False) != "", 20, "slurmctld.log",
                       "slurmctld did not answer")
            self._spawn("slurmd.out", ["slurmd", "-D", "-N", self.NODE])
            self._wait(lambda: self.run("sinfo", "-h", "-o", "%t", check=False).strip() == "idle", timeout,
                       "slurmd.log", "the node did not come up idle")
        except BaseException:
            self.stop()
            raise
        return self

    def _wait(self, ready, timeout, log, what):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for p in self.procs:
                if p.poll() is not None:
                    raise RuntimeError(f"{Path(p.args[0]).name} exited with status {p.returncode}:\n"
                                       f"{self.log(log)}")
            if ready():
                return
            time.sleep(0.2)
        raise RuntimeError(f"{what} within {timeout:g} s:\n{self.log(log)}")

    # ------------------------------------------------------------------ use
    def jobs(self) -> list[str]:
        """Ids of the jobs in the queue (pending or running)."""
        return self.run("squeue", "-h", "-o", "%i", check=False).split()

    def active(self) -> list[str]:
        """Ids of the jobs pending or running (not those being ended: state CG)."""
        return self.run("squeue", "-h", "-t", "PD,R", "-o", "%i", check=False).split()

    def jobs_end(self, timeout: float = 30.0) -> bool:
        """Whether the queue is empty within ``timeout`` seconds (a cancelled job stays
        listed while its processes are being ended)."""
        deadline = time.monotonic() + timeout
        while self.jobs():
            if time.monotonic() > deadline:
                return False
            time.sleep(0.2)
        return True

    def stop(self) -> None:
        if self.procs and all(p.poll() is None for p in self.procs[:2]) and len(self.procs) == 3:
            ids = self.jobs()
            if ids:
                self.run("scancel", *ids, check=False)
                deadline = time.monotonic() + 20
                while self.jobs() and time.monotonic() < deadline:
                    time.sleep(0.3)
        for p in reversed(self.procs):         # slurmd, slurmctld, munged
            if p.poll() is None:
                p.terminate()
                try:
                    p.wait(timeout=15)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
        self.procs = []
