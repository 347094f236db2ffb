"""Shared fixtures: bundled specs and their designs, built once per session."""

from __future__ import annotations

import sys
from functools import lru_cache
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

from stt_codegen.design.search import design_tube  # noqa: E402
from stt_codegen.spec.loader import bundled_cases, load_spec  # noqa: E402

CASES = ["omnirobot-s1", "omnirobot-s2", "omnirobot-s3"]


@lru_cache(maxsize=None)
def designed(name: str):
    """``(spec, design, check)`` of a bundled case, cached."""
    spec = load_spec(name)
    found = design_tube(spec)
    design, check = found.tube, found.check
    return spec, design, check


@lru_cache(maxsize=None)
def model_of(name: str):
    from stt_codegen.tube.model import build_model
    return build_model(designed(name)[1])


@pytest.fixture(params=CASES)
def case(request):
    return request.param


def test_bundled_cases_are_the_paper_cases():
    assert bundled_cases() == CASES
