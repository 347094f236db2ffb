"""``.ci/run`` stops at the first failing step and names it.

A copy of the script runs in a scratch tree whose tools are stand-ins: ``python3`` logs
its arguments and succeeds, ``stt-codegen`` fails, ``.ci/apt-install`` does nothing. The
copy must exit non-zero at ``stt-codegen check``, say so, and never start the fast tier.
"""

from __future__ import annotations

import os
import shutil
import stat
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CHECK_FAILED = "FAILED at step: stt-codegen check (generated/ is current)"


def _script(path: Path, body: str) -> None:
    path.write_text("#!/usr/bin/env bash\n" + body)
    path.chmod(path.stat().st_mode | stat.S_IEXEC)


def _run_copy(tmp_path: Path, check_status: int) -> tuple[subprocess.CompletedProcess, str]:
    tree = tmp_path / "tree"
    (tree / ".ci").mkdir(parents=True)
    shutil.copy(REPO / ".ci" / "run", tree / ".ci" / "run")
    _script(tree / ".ci" / "apt-install", "exit 0\n")
    tools = tmp_path / "bin"
    tools.mkdir()
    log = tmp_path / "calls.log"
    _script(tools / "python3", f'echo "python3 $*" >> "{log}"\nexit 0\n')
    _script(tools / "stt-codegen", f'echo "stt-codegen $*" >> "{log}"\nexit {check_status}\n')
    env = dict(os.environ, PATH=f"{tools}{os.pathsep}{os.environ['PATH']}")
    done = subprocess.run(["bash", str(tree / ".ci" / "run")], env=env, capture_output=True,
                          text=True, timeout=60)
    return done, log.read_text() if log.exists() else ""


def test_a_failing_check_stops_ci_and_is_named(tmp_path):
    done, calls = _run_copy(tmp_path, check_status=1)
    assert done.returncode != 0
    assert CHECK_FAILED in done.stderr
    assert "stt-codegen check" in calls
    assert "-m pytest" not in calls, "the fast tier ran after stt-codegen check failed"


def test_with_every_step_passing_ci_reaches_the_tiers(tmp_path):
    """The same stand-ins with a passing check: the run goes on to both pytest runs (it
    stops later, at the first step needing a venv, which the stand-in does not make)."""
    done, calls = _run_copy(tmp_path, check_status=0)
    assert "python3 -m pytest -q\n" in calls
    assert 'python3 -m pytest -q -m slow or embedded or bench' in calls
    assert CHECK_FAILED not in done.stderr
