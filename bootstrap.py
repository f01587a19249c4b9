#!/usr/bin/env python3
"""Set up the project's virtual environment and run a command in it (stdlib only).

Usage:
    python3 bootstrap.py test [pytest args...]   # default pytest args: -n 2 --durations=30
    python3 bootstrap.py demo [demo args...]     # runs `cracklab demo ...`
    python3 bootstrap.py docs [sphinx args...]   # builds the site into docs/_build/html

The environment lives in .venv and is installed from environment.lock (pinned,
hashed), then the project itself is installed editable without dependencies.
A stamp file in .venv records the hash of environment.lock and pyproject.toml;
the install is skipped while neither has changed. See docs/guide/environment.md.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import NoReturn

ROOT = Path(__file__).resolve().parent
VENV = ROOT / ".venv"
VENV_PYTHON = VENV / "bin" / "python"
LOCK = ROOT / "environment.lock"
PYPROJECT = ROOT / "pyproject.toml"
STAMP = VENV / "cracklab-install.stamp"
# Bump to force a reinstall when the install procedure itself changes.
STAMP_FORMAT = "1"

#: Debian packages the tests start services from (tests/slurm.py: a one-node Slurm on
#: loopback for the sweep on batch jobs), installed by `test` when missing, as root, with
#: apt-get; the commands that show them installed
SYSTEM_PACKAGES = ("slurmctld", "slurmd", "slurm-client", "munge")
SYSTEM_COMMANDS = ("munged", "slurmctld", "slurmd", "sbatch")

USAGE = "usage: python3 bootstrap.py {test|demo|docs} [args...]"
SITE = ROOT / "docs" / "_build" / "html"


def say(msg: str) -> None:
    print(f"cracklab: {msg}", flush=True)


def fail(msg: str, code: int = 1) -> NoReturn:
    print(f"cracklab: error: {msg}", file=sys.stderr, flush=True)
    sys.exit(code)


def run(cmd: list[str]) -> None:
    """Run a setup command; on failure report it and exit with its code."""
    rc = subprocess.call(cmd, cwd=ROOT, stdin=subprocess.DEVNULL)
    if rc != 0:
        fail(f"command failed (exit {rc}): {' '.join(cmd)}", rc if rc > 0 else 1)


def wanted_stamp() -> str:
    h = hashlib.sha256()
    h.update(f"stamp-format {STAMP_FORMAT}\n".encode())
    for path in (LOCK, PYPROJECT):
        data = path.read_bytes()
        h.update(f"{path.name} {len(data)}\n".encode())
        h.update(data)
    return h.hexdigest()


def ensure_venv() -> None:
    if VENV_PYTHON.exists():
        return
    say("creating .venv")
    # --clear only matters for a half-made .venv left behind by an interrupted run.
    run([sys.executable, "-m", "venv", "--clear", str(VENV)])


def ensure_installed() -> None:
    for path in (LOCK, PYPROJECT):
        if not path.is_file():
            fail(f"missing {path.name}")
    stamp = wanted_stamp()
    if STAMP.is_file() and STAMP.read_text().strip() == stamp:
        say("environment up to date (environment.lock and pyproject.toml unchanged)")
        return

    # Drop any old stamp first so an interrupted install is redone next time.
    STAMP.unlink(missing_ok=True)
    pip = [str(VENV_PYTHON), "-m", "pip", "--disable-pip-version-check", "--no-input"]
    t0 = time.monotonic()
    say("installing from environment.lock")
    run(pip + ["install", "-q", "--require-hashes", "-r", str(LOCK)])
    say("installing cracklab (editable, --no-deps)")
    run(pip + ["install", "-q", "--no-deps", "--no-build-isolation", "-e", str(ROOT)])
    # Catches a lock that no longer covers what pyproject.toml declares.
    check = subprocess.run(pip + ["check"], cwd=ROOT, stdin=subprocess.DEVNULL,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if check.returncode != 0:
        sys.stderr.write(check.stdout)
        fail("`pip check` failed: environment.lock does not satisfy pyproject.toml "
             "(regenerate it, see docs/guide/environment.md)", check.returncode)
    STAMP.write_text(stamp + "\n")
    say(f"environment ready ({time.monotonic() - t0:.0f} s)")


def in_ci() -> bool:
    return os.environ.get("CI", "").lower() in ("true", "1")


def ensure_system_packages() -> None:
    """Install SYSTEM_PACKAGES with apt-get when a command of theirs is missing. Without
    root or apt-get, say so and go on (the tests that need them are skipped, saying why);
    in CI (CI=true) a failed install stops the run."""
    import shutil

    found = lambda c: shutil.which(c) or shutil.which(c, path="/usr/sbin:/sbin")  # noqa: E731
    if all(found(c) for c in SYSTEM_COMMANDS):
        return
    names = " ".join(SYSTEM_PACKAGES)
    if os.geteuid() != 0 or shutil.which("apt-get") is None:
        why = "not root" if os.geteuid() != 0 else "no apt-get"
        if in_ci():
            fail(f"CI needs the Debian packages {names} for the cluster tests, and cannot install them ({why})")
        say(f"the cluster tests need the Debian packages {names}, not installed ({why}): those tests are "
            f"skipped (as root: apt-get install {names})")
        return
    t0 = time.monotonic()
    say(f"installing the Debian packages {names} (a one-node Slurm for the cluster tests)")
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    for cmd in (["apt-get", "update", "-q"],
                ["apt-get", "install", "-y", "-q", "--no-install-recommends", *SYSTEM_PACKAGES]):
        res = subprocess.run(cmd, cwd=ROOT, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True, env=env)
        if res.returncode != 0:
            sys.stderr.write(res.stdout[-4000:])
            if in_ci():
                fail(f"command failed (exit {res.returncode}): {' '.join(cmd)}", res.returncode)
            say(f"could not install {names} (the output above says why): the cluster tests are skipped")
            return
    say(f"Debian packages installed ({time.monotonic() - t0:.0f} s)")


def exec_in_venv(argv: list[str]) -> NoReturn:
    """Replace this process with argv, so its exit code is ours."""
    sys.stdout.flush()
    sys.stderr.flush()
    os.chdir(ROOT)
    try:
        os.execv(argv[0], argv)
    except OSError as exc:
        fail(f"cannot run {argv[0]}: {exc}")


def main(args: list[str]) -> None:
    if sys.version_info < (3, 11):
        fail(f"Python >= 3.11 required, this is {sys.version.split()[0]}")
    if not args or args[0] not in ("test", "demo", "docs"):
        print(USAGE, file=sys.stderr)
        sys.exit(2)
    command, extra = args[0], args[1:]

    ensure_venv()
    ensure_installed()

    if command == "test":
        ensure_system_packages()
        say("running tests")
        pytest_args = extra if extra else ["-n", "2", "--durations=30"]   # the slowest, for the CI budget
        exec_in_venv([str(VENV_PYTHON), "-m", "pytest", *pytest_args])
    elif command == "demo":
        say("running demo")
        exec_in_venv([str(VENV / "bin" / "cracklab"), "demo", *extra])
    else:
        say(f"building the documentation site into {SITE.relative_to(ROOT)}")
        # as CI builds it (tests/docs/test_site.py): warnings are errors, references checked
        rc = subprocess.call([str(VENV_PYTHON), "-m", "sphinx", "-W", "--keep-going", "-n", "-b", "html",
                              "-d", str(SITE.parent / "doctrees"), *extra, "docs", str(SITE)],
                             cwd=ROOT, stdin=subprocess.DEVNULL)
        if rc != 0:
            fail("the site did not build (the messages above say why)", rc)
        say(f"open {(SITE / 'index.html').as_uri()} in a browser")


if __name__ == "__main__":
    main(sys.argv[1:])
