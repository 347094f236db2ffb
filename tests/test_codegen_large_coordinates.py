"""Large coordinates: ``generate`` finishes, double works, single says why not, every variant.

``sample_inputs`` looked, without bound, for test points whose single-precision status is
certain; with the tube narrower than about ``4 * 64 * 2^-24`` times the largest coordinate
none qualifies and ``generate`` never finished, in double too. Now the search is bounded
(``ROUNDS`` rounds of ``BATCH`` candidates: counted here, not timed), certainty is judged
in the generated precision, and single precision on these arenas is a ``SpecError``
naming ``precision`` (exit 2, one line, nothing written). The command-line runs are in
the slow tier, with a generous timeout that only guards against a hang, for every
controller variant: the arenas driven by a double integrator (``-cascade``) and by a
differential-drive base (``-drive``, tests/specs/). The bounded search itself is the
first order's test vectors' (:func:`stt_codegen.codegen.vectors.sample_inputs`).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from codegen_helpers import COMPILERS

from stt_codegen.codegen import tolerance, vectors
from stt_codegen.design.search import design_tube
from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import load_spec

SPECS = Path(__file__).parent / "specs"
ARENAS = ["shifted-arena-1e6", "wide-arena-20km"]
#: The spec name of an arena for each controller variant.
VARIANT_SUFFIX = {"first-order": "", "cascade": "-cascade", "look-ahead": "-drive"}
#: The specs of the command-line runs: every arena for every variant.
SPEC_RUNS = [arena + suffix for suffix in VARIANT_SUFFIX.values() for arena in ARENAS]
#: A command that has not finished after this many seconds hangs (they take a few).
HANG = 600


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).parents[1]))
    try:
        return subprocess.run([sys.executable, "-m", "stt_codegen.cli", *args], cwd=cwd,
                              env=env, capture_output=True, text=True, timeout=HANG)
    except subprocess.TimeoutExpired:
        pytest.fail(f"stt-codegen {' '.join(args)} did not finish in {HANG} s: a hang "
                    "(an unbounded search for test points?)")


@pytest.mark.parametrize("arena", ARENAS)
def test_the_search_for_test_points_is_bounded(arena, monkeypatch):
    """Single precision gives up after ``ROUNDS`` rounds with the reason; double finds its
    points within them (the bound does not cost the precision that works). The budget is
    at most 12 800 candidates (about a second of work)."""
    assert vectors.ROUNDS * vectors.BATCH <= 12_800
    design = design_tube(load_spec(SPECS / f"{arena}.toml")).tube
    rounds = [0]
    original = tolerance.status_certain

    def counted(*args, **kwargs):          # called once per round, on its BATCH candidates
        rounds[0] += 1
        return original(*args, **kwargs)

    monkeypatch.setattr(tolerance, "status_certain", counted)
    with pytest.raises(SpecError) as info:
        vectors.sample_inputs(design, "single")
    assert info.value.field == "precision" and "use precision double" in info.value.reason
    assert rounds[0] == vectors.ROUNDS
    rounds[0] = 0
    points = vectors.sample_inputs(design, "double")
    assert len(points["t"]) == vectors.INSIDE + vectors.OUTSIDE
    assert 0 < rounds[0] <= vectors.ROUNDS


@pytest.mark.slow
@pytest.mark.skipif(not COMPILERS, reason="no C compiler (Debian: gcc)")
@pytest.mark.parametrize("arena", SPEC_RUNS)
def test_double_generates_and_its_selftest_passes(arena, tmp_path):
    proc = _cli("generate", str(SPECS / f"{arena}.toml"), "-o", "out", "--precision", "double",
                cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    make = subprocess.run(["make", "-s", "selftest", f"CC={COMPILERS[0]}"], cwd=tmp_path / "out",
                          capture_output=True, text=True, timeout=HANG)
    assert make.returncode == 0, make.stderr
    assert make.stdout.strip().splitlines()[-1].endswith(" 0 failed"), make.stdout[-300:]


@pytest.mark.slow
@pytest.mark.parametrize("arena", SPEC_RUNS)
def test_single_is_refused_with_the_reason(arena, tmp_path):
    proc = _cli("generate", str(SPECS / f"{arena}.toml"), "-o", "out", "--precision", "single",
                cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr
    assert "single precision cannot resolve a tube of width" in lines[0]
    assert "use precision double" in lines[0]
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


@pytest.mark.slow
@pytest.mark.skipif(not COMPILERS, reason="no C compiler (Debian: gcc)")
@pytest.mark.parametrize("arena", SPEC_RUNS)
def test_simulate_with_the_c_backend(arena, tmp_path):
    proc = _cli("simulate", str(SPECS / f"{arena}.toml"), "--backend", "c", "--json",
                cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert '"satisfied": true' in proc.stdout and '"stayed_in_tube": true' in proc.stdout
