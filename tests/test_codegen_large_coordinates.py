"""Large coordinates (issue 23.1): ``generate`` finishes, double works, single says why not.

``sample_inputs`` looked, without bound, for test points whose single-precision status is
certain; with the tube narrower than about ``4 * 64 * 2^-24`` times the largest coordinate
none qualifies and ``generate`` never finished, in double too. Now the search is bounded,
certainty is judged in the generated precision, and single precision on these arenas is a
``SpecError`` naming ``precision`` (exit 2, one line, nothing written).
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from codegen_helpers import COMPILERS

SPECS = Path(__file__).parent / "specs"
ARENAS = ["shifted-arena-1e6", "wide-arena-20km"]
#: Acceptance: generate and simulate finish within this many seconds.
LIMIT = 30.0

pytestmark = pytest.mark.slow


def _cli(*args: str, cwd: Path) -> tuple[subprocess.CompletedProcess, float]:
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).parents[1]))
    start = time.monotonic()
    proc = subprocess.run([sys.executable, "-m", "stt_codegen.cli", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=2 * LIMIT)
    return proc, time.monotonic() - start


@pytest.mark.skipif(not COMPILERS, reason="no C compiler (Debian: gcc)")
@pytest.mark.parametrize("arena", ARENAS)
def test_double_generates_and_its_selftest_passes(arena, tmp_path):
    proc, seconds = _cli("generate", str(SPECS / f"{arena}.toml"), "-o", "out",
                         "--precision", "double", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert seconds < LIMIT
    make = subprocess.run(["make", "-s", "selftest", f"CC={COMPILERS[0]}"], cwd=tmp_path / "out",
                          capture_output=True, text=True)
    assert make.returncode == 0, make.stderr
    assert make.stdout.strip().splitlines()[-1].endswith(" 0 failed"), make.stdout[-300:]


@pytest.mark.parametrize("arena", ARENAS)
def test_single_is_refused_with_the_reason(arena, tmp_path):
    proc, seconds = _cli("generate", str(SPECS / f"{arena}.toml"), "-o", "out",
                         "--precision", "single", cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert seconds < LIMIT
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr
    assert "single precision cannot resolve a tube of width" in lines[0]
    assert "use precision double" in lines[0]
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


@pytest.mark.skipif(not COMPILERS, reason="no C compiler (Debian: gcc)")
@pytest.mark.parametrize("arena", ARENAS)
def test_simulate_with_the_c_backend(arena, tmp_path):
    proc, seconds = _cli("simulate", str(SPECS / f"{arena}.toml"), "--backend", "c", "--json",
                         cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert seconds < LIMIT
    assert '"satisfied": true' in proc.stdout and '"stayed_in_tube": true' in proc.stdout

