"""Shared fixtures: bundled specs and their designs, a spec factory, the Hypothesis profile."""

from __future__ import annotations

import os
import sys
from functools import lru_cache
from pathlib import Path

import pytest
from hypothesis import settings

sys.path.insert(0, str(Path(__file__).parent))

from stt_codegen.design.search import design_tube  # noqa: E402
from stt_codegen.spec.loader import load_spec  # noqa: E402

CASES = ["omnirobot-s1", "omnirobot-s2", "omnirobot-s3"]
#: The bundled examples of timed tasks (docs/tasks.md), besides the paper's.
TASK_CASES = ["tasks-stay", "tasks-visit"]
#: The bundled examples of moving obstacles (docs/moving-obstacles.md), of a plant on
#: MuJoCo (docs/mujoco.md) and of obstacles sensed at run time (docs/sensing.md).
EXTRA_CASES = ["crossing-moving", "hall-crossing", "pointmaze-umaze"]

# Property tests draw the same examples on every run: a fixed seed (derandomize) and no
# example database. "ci" is the default and the only profile under CI (CI=true);
# HYPOTHESIS_PROFILE=explore draws fresh random examples for a local bug hunt. A test's
# own @settings still sets max_examples and deadline; it inherits derandomize from the
# loaded profile.
settings.register_profile("ci", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile("ci" if os.environ.get("CI") else os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@lru_cache(maxsize=None)
def design_of(name: str):
    """The :class:`~stt_codegen.design.result.Design` of a bundled case, cached (what the
    front door's ``generate``, ``simulate``, ``verify`` and plots take)."""
    return design_tube(load_spec(name))


def designed(name: str):
    """``(spec, tube, check)`` of a bundled case, cached: the parts of :func:`design_of`,
    for the internal functions that take them apart."""
    found = design_of(name)
    return found.spec, found.tube, found.check


@lru_cache(maxsize=None)
def model_of(name: str):
    from stt_codegen.tube.model import build_model
    return build_model(designed(name)[1])


def arena_toml(name: str, prescribed_time: float = 9.0, extra: str = "",
               target: tuple[tuple[float, float], tuple[float, float]] = ((4.5, 4.5), (5.0, 5.0)),
               ) -> str:
    """The text of a 2-D test spec: the 5 m x 5 m arena, start ``[0, 0.5]^2``, a target box.

    ``extra`` is appended (obstacles, ``[tube]``, ``[controller]``, ``[plant]``...). The
    tables are written one key per line, so tests may edit the text with ``str.replace``.
    The one factory of 2-D test specs; a plain function (``from conftest import
    arena_toml``) because its users are module-level constants and parametrize lists,
    which pytest fixtures cannot reach.
    """
    (lo0, lo1), (hi0, hi1) = target
    return (f'\nname = "{name}"\nprescribed_time = {float(prescribed_time)!r}\n'
            "[state_space]\nlower = [0.0, 0.0]\nupper = [5.0, 5.0]\n"
            "[initial]\nlower = [0.0, 0.0]\nupper = [0.5, 0.5]\n"
            f"[target]\nlower = [{lo0!r}, {lo1!r}]\nupper = [{hi0!r}, {hi1!r}]\n" + extra)


@pytest.fixture(params=CASES)
def case(request):
    return request.param


def pytest_runtest_setup(item):
    """A test marked ``embedded`` needs the Cortex-M toolchain and QEMU: without them it is
    skipped, and the message names the Debian packages to install."""
    if item.get_closest_marker("embedded") is not None:
        from stt_codegen.embedded import missing_message
        message = missing_message()
        if message:
            pytest.skip("embedded toolchain: " + message)
