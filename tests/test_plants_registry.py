"""The plant registry: every behaviour is a lookup keyed by ``plant.model``, complete for
every registered model, and a model without a behaviour is refused by name."""

from __future__ import annotations

import pytest

import stt_codegen as stt
from stt_codegen.errors import SpecError
from stt_codegen.runtime.dynamics import INPUT_MATRICES
from stt_codegen.runtime.plants import SIMULATION_PLANTS
from stt_codegen.runtime.second_order_plants import ACCELERATIONS
from stt_codegen.spec.model_bounds import BOX_BOUNDS
from stt_codegen.spec.plants import (MODEL_KEYS, PLANT_MODELS, SECOND_ORDER_MODELS,
                                     MissingPlantBehaviour, model_behaviour, plant_entry)
from stt_codegen.proofs.assumption import ASSUMPTION2_CHECKS, assumption2_check


def test_every_first_order_model_has_every_behaviour():
    matrices_from_spec = set(MODEL_KEYS.values())
    for model in PLANT_MODELS:
        entry = plant_entry(model)
        assert entry.order == 1
        assert model in ASSUMPTION2_CHECKS, model
        assert model in SIMULATION_PLANTS, model
        if entry.declared_bounds:       # no equations (MuJoCo): nothing derived or printed
            assert model not in BOX_BOUNDS and model not in INPUT_MATRICES, model
            assert entry.simulator_keys, model
            continue
        assert model in BOX_BOUNDS, model
        if entry.plant_states is not None:   # the tube holds a point of the plant's state:
            assert model not in INPUT_MATRICES, model   # its g is the variant's, no g(x)
            continue
        # g(x) is the registry's unless the spec gives the matrices
        assert (model in INPUT_MATRICES) != (model in matrices_from_spec), model


def test_every_second_order_model_has_its_dynamics():
    for model in SECOND_ORDER_MODELS:
        assert plant_entry(model).order == 2
        # a model without equations (MuJoCo) has none to print
        assert (model in ACCELERATIONS) != plant_entry(model).declared_bounds, model


def test_the_tables_hold_no_unregistered_model():
    known = set(PLANT_MODELS) | set(SECOND_ORDER_MODELS)
    for table in (BOX_BOUNDS, ASSUMPTION2_CHECKS, SIMULATION_PLANTS, INPUT_MATRICES,
                  ACCELERATIONS):
        assert set(table) <= known


def test_a_missing_behaviour_is_refused_by_name():
    with pytest.raises(MissingPlantBehaviour, match=r"'new-robot' has no dynamics "
                                                    r"\(models with one: a, b\)"):
        model_behaviour({"a": 1, "b": 2}, "new-robot", "dynamics")
    with pytest.raises(MissingPlantBehaviour, match="'new-robot'"):
        plant_entry("new-robot")


def test_a_model_without_an_assumption2_check_is_refused_not_checked_as_another():
    spec = stt.load_spec("omnirobot-s1")
    with pytest.raises(SpecError, match="new-robot.*no Assumption-2 check") as err:
        assumption2_check(spec, "new-robot")
    assert err.value.field == "plant.model"


@pytest.mark.parametrize("model, name", [("omnidirectional", "assumption2.omnidirectional"),
                                         ("single-integrator",
                                          "assumption2.single_integrator"),
                                         ("linear", "assumption2.linear")])
def test_each_model_gets_its_own_assumption2_check(model, name):
    spec = stt.load_spec("omnirobot-s1")
    check = assumption2_check(spec, model)
    assert check.name == name
    assert check.passed
