"""The test tiers (docs/testing.md): the default run is the fast tier, ``.ci/run`` the rest.

Every marker declared in pyproject.toml is deselected by its ``addopts`` and selected by
the second pytest run of ``.ci/run``, so each test runs in CI exactly once, and some test
carries each marker, so that run always finds tests (pytest exits 5 when it finds none).
"""

from __future__ import annotations

import shlex
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CONFIG = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
MARKERS = [line.split(":")[0] for line in CONFIG["markers"]]


def test_the_tiers_are_slow_embedded_and_bench():
    assert MARKERS == ["slow", "embedded", "bench"]


def test_the_default_run_deselects_every_tier():
    options = shlex.split(CONFIG["addopts"])
    assert "--strict-markers" in options
    assert options[options.index("-m") + 1] == " and ".join(f"not {m}" for m in MARKERS)


def test_the_default_run_uses_every_cpu_a_file_to_a_worker():
    options = shlex.split(CONFIG["addopts"])
    assert options[options.index("-n") + 1] == "auto"
    assert options[options.index("--dist") + 1] == "loadfile"


def test_ci_runs_the_other_tiers_after_the_readme_command():
    lines = (REPO / ".ci" / "run").read_text().splitlines()
    fast = lines.index("python3 -m pytest -q")
    rest = lines.index(f'python3 -m pytest -q -m "{" or ".join(MARKERS)}"')
    assert fast < rest


def test_every_tier_holds_tests():
    text = "".join(p.read_text() for p in sorted((REPO / "tests").glob("test_*.py")))
    for marker in MARKERS:
        assert f"pytest.mark.{marker}" in text, marker
