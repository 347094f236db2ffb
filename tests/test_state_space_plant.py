"""A python-control StateSpace as the ``linear`` plant of a spec given as a dict: the same spec
as the matrices written out; each misuse refused naming ``plant.system``."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

import control as ct

import stt_codegen as stt

SPEC = tomllib.loads((Path(__file__).parent / "specs" / "linear-arena-s1.toml").read_text())


def _with_plant(plant: dict) -> dict:
    return {**SPEC, "plant": {k: v for k, v in {**SPEC["plant"], **plant}.items()
                              if v is not None}}


def test_a_state_space_is_the_linear_plant_of_its_a_and_b() -> None:
    a, g = np.array(SPEC["plant"]["a"]), np.array(SPEC["plant"]["g"])
    n = a.shape[0]
    given = stt.Spec.from_dict(_with_plant({"a": None, "g": None,
                                            "system": ct.ss(a, g, np.eye(n), 0)}))
    written = stt.Spec.from_dict(SPEC)
    assert given.linear_plant == written.linear_plant
    assert given.linear_plant.a == tuple(map(tuple, a.tolist()))
    assert given == written          # the same spec (the hash aside, which compare skips)


@pytest.mark.parametrize("system, extra, reason", [
    (ct.ss(-np.eye(3), np.eye(3), np.eye(3), 0, dt=0.01), {}, "continuous-time"),
    (ct.ss(-np.eye(3), np.ones((3, 1)), np.eye(3), 0), {}, "B must be 3 x 3"),
    (ct.ss(-np.eye(3), np.eye(3), np.ones((1, 3)), 0), {}, "C must be the identity"),
    (ct.ss(-np.eye(3), np.eye(3), np.eye(3), 0), {"model": "single-integrator"},
     'only plant.model = "linear"'),
    (ct.ss(-np.eye(3), np.eye(3), np.eye(3), 0), {"keep_a": True}, "not both"),
    ("not a system", {}, "must be a control.StateSpace"),
])
def test_each_misuse_names_plant_system(system, extra, reason) -> None:
    plant = {"system": system, "g": None}
    if not extra.pop("keep_a", False):
        plant["a"] = None
    plant.update(extra)
    if plant.get("model") == "single-integrator":
        plant["c"] = None
    with pytest.raises(stt.SpecError) as info:
        stt.Spec.from_dict(_with_plant(plant))
    assert info.value.field == "plant.system"
    assert reason in str(info.value)
