"""``.ci/apt-install`` waits for apt's locks instead of failing at once (exit 100)."""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
import threading
import time
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parent.parent / ".ci" / "apt-install"
LOCKS = ("/var/lib/dpkg/lock-frontend", "/var/lib/apt/lists/lock")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(shutil.which("apt-get") is None, reason="needs apt-get (Debian)"),
    pytest.mark.skipif(hasattr(os, "geteuid") and os.geteuid() != 0,
                       reason="needs root to take apt's locks"),
]


def test_install_waits_for_a_held_apt_lock(tmp_path: Path) -> None:
    # make the script believe `make` (installed everywhere CI runs) is missing, so that it
    # runs the real apt-get update and install while another process holds both locks
    fake = tmp_path / "dpkg-query"
    fake.write_text("#!/bin/sh\necho 'deinstall ok config-files'\n")
    fake.chmod(0o755)
    held = [os.open(path, os.O_RDWR | os.O_CREAT) for path in LOCKS]
    for fd in held:
        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    hold_s = 3.0
    release = threading.Timer(hold_s, lambda: [os.close(fd) for fd in held])
    started = time.monotonic()
    release.start()
    try:
        run = subprocess.run(["bash", str(SCRIPT), "make"], capture_output=True, text=True,
                             env={**os.environ, "PATH": f"{tmp_path}:{os.environ['PATH']}",
                                  "STT_APT_LOCK_WAIT_S": "120"}, timeout=300)
    finally:
        release.join()
    assert run.returncode == 0, run.stderr
    assert time.monotonic() - started >= hold_s
