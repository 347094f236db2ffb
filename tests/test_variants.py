"""The controller variants, registered once (stt_codegen/spec/variants.py): the lookups that
replace the branches on ``order``, ``variant``, ``drive`` and ``stage``."""

from __future__ import annotations

import numpy as np
import pytest

from stt_codegen.errors import SpecError
from stt_codegen.runtime import backends
from stt_codegen.runtime.simulate import run_closed_loop
from stt_codegen.spec.plants import PLANTS, SECOND_ORDER_PLANTS
from stt_codegen.spec.variants import (CONTROLLER_VARIANTS, require_variant, variant_named,
                                       variant_of, variant_of_order, variant_of_stage)
from stt_codegen.tube.look_ahead import LookAhead
from stt_codegen.tube.second_stage import SecondStage

from conftest import design_of

STAGE = SecondStage(position_gain=0.02, velocity_gain=3.0, width_start=(1.5, 1.2),
                    width_floor=(0.3, 0.25), decay=2.0)


def test_every_plant_model_names_a_registered_variant():
    for entry in (*PLANTS.values(), *SECOND_ORDER_PLANTS.values()):
        assert variant_of(entry).name == entry.variant
    assert variant_of(SECOND_ORDER_PLANTS["quadrotor"]) is CONTROLLER_VARIANTS["cascade"]
    assert variant_of(PLANTS["differential-drive"]) is CONTROLLER_VARIANTS["look-ahead"]


def test_an_unknown_variant_or_order_names_its_field():
    with pytest.raises(SpecError, match="unknown controller variant 'bicycle'") as err:
        variant_named("bicycle")
    assert err.value.field == "variant"
    with pytest.raises(SpecError) as err:
        variant_of_order(3)
    assert err.value.field == "order"
    assert variant_of_order(2) is CONTROLLER_VARIANTS["cascade"]


def test_the_stage_decides_the_variant_of_a_controller():
    assert variant_of_stage(None) is CONTROLLER_VARIANTS["first-order"]
    assert variant_of_stage(STAGE) is CONTROLLER_VARIANTS["cascade"]
    assert variant_of_stage(LookAhead(0.1)) is CONTROLLER_VARIANTS["look-ahead"]
    with pytest.raises(SpecError, match="no controller variant takes a str") as err:
        variant_of_stage("stage")
    assert err.value.field == "stage"


def test_the_state_layout_of_each_variant():
    first, cascade, base = (CONTROLLER_VARIANTS[n] for n in ("first-order", "cascade",
                                                             "look-ahead"))
    assert (first.state_blocks, cascade.state_blocks, base.state_blocks) == (1, 2, 1)
    assert cascade.state_words == " (positions, then velocities)" and first.state_words == ""


def test_a_first_order_design_refuses_what_only_another_variant_has():
    design = design_of("omnirobot-s1")
    assert design.stage is None
    with pytest.raises(SpecError, match="a look-ahead point needs a differential-drive base "
                                        "\\(the look-ahead variant\\); the spec describes a "
                                        "first-order plant \\(the first-order variant\\)"
                       ) as err:
        design.look_ahead
    assert err.value.field == "plant.model"
    with pytest.raises(SpecError) as err:
        require_variant(design.spec, "cascade", "the cascade's closed loop")
    assert err.value.field == "plant.model"
    require_variant(design.spec, "first-order", "law (13)")       # its own: no error


def test_a_stage_of_another_variant_is_refused_by_the_loop():
    design = design_of("omnirobot-s1")
    with pytest.raises(SpecError, match="first-order variant runs law \\(13\\) with its own "
                                        "stage .*not a LookAhead") as err:
        run_closed_loop(design.spec, design.tube, stage=LookAhead(0.1), horizon=0.1)
    assert err.value.field == "stage"


def test_make_controller_follows_the_stage_and_names_the_plant_kind():
    design = design_of("omnirobot-s1")
    controller = backends.make_controller("reference", design.tube)
    u, alpha, status = controller.step(np.array(design.spec.initial_state), 0.0,
                                       1.0 / design.tube.rate_hz, np.zeros(6))
    assert u.shape == (3,) and alpha.shape == (6,) and status == 0
    with pytest.raises(SpecError, match="unknown backend 'nope' for a second-order plant"):
        backends.make_controller("nope", design.tube, STAGE)
    with pytest.raises(SpecError, match="for a differential-drive base"):
        backends.make_controller("nope", design.tube, LookAhead(0.1))
    assert backends.backend_names(variant="look-ahead") == ["reference", "casadi", "c",
                                                            "python"]
