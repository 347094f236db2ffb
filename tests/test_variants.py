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


def test_stt_codegen_embedded_runs_the_variants_own_firmware_loop(monkeypatch, capsys):
    """The command asks the spec's variant for its firmware loop (role ``firmware``,
    resolved on use): a differential-drive spec runs the look-ahead loop, never law
    (13)'s ``run_embedded``."""
    from pathlib import Path

    from stt_codegen.cli import main
    from stt_codegen.embedded import deploy, look_ahead_loop

    calls = []

    def loop(design, seed=0, timeout=600.0):
        calls.append((design.spec.name, seed))
        return {"satisfied": True, "reach_time": 1.5, "min_clearance": 0.25,
                "instructions_per_step": 1234}

    def law13(*args, **kwargs):
        raise AssertionError("law (13)'s firmware loop run for a differential-drive spec")

    monkeypatch.setattr(look_ahead_loop, "run_look_ahead_embedded", loop)
    monkeypatch.setattr(deploy, "run_embedded", law13)
    spec = Path(__file__).parent / "specs" / "office-drive.toml"
    assert main(["embedded", str(spec), "--seed", "3"]) == 0
    assert len(calls) == 1 and calls[0][1] == 3
    assert "(look-ahead) on the Cortex-M4F" in capsys.readouterr().out


def _variant_cases():
    """``(variant, tube, stage, x)`` of each variant: omnirobot-s1 (law (13) and, with a
    hand-made second stage, the cascade on its tube) and the office's base."""
    from pathlib import Path

    import stt_codegen as stt
    from stt_codegen.runtime.state_split import initial_state

    s1 = design_of("omnirobot-s1")
    stage = SecondStage(position_gain=0.02, velocity_gain=3.0, width_start=(1.5, 1.2, 0.9),
                        width_floor=(0.3, 0.25, 0.2), decay=2.0)
    office = stt.design_tube(stt.load_spec(str(Path(__file__).parent / "specs"
                                               / "office-drive.toml")))
    x1 = np.array(s1.spec.initial_state)
    return [("first-order", s1.tube, None, x1),
            ("cascade", s1.tube, stage, np.concatenate([x1, [0.05, -0.02, 0.01]])),
            ("look-ahead", office.tube, office.stage, initial_state(office.spec))]


def test_each_variants_deployed_step_is_its_oracles():
    """The roles ``casadi_step`` and ``oracle_step`` of each variant give the same step:
    ``u`` and ``alpha_next`` at the start and half a second later, with ``alpha`` away
    from zero."""
    for name, tube, stage, x in _variant_cases():
        variant = CONTROLLER_VARIANTS[name]
        function = variant.entry("casadi_step")(tube, stage)
        oracle = variant.entry("oracle_step")
        n, dt = tube.dimension, 1.0 / tube.rate_hz
        for t, alpha in ((0.0, np.zeros(2 * n)), (0.5, np.linspace(0.01, 0.05, 2 * n))):
            u, alpha_next = (np.array(v, dtype=float).ravel()
                             for v in function(x, t, dt, alpha)[:2])
            u_ref, alpha_ref = (np.asarray(v)[0] for v in
                                oracle(tube, stage, x[None], np.array([t]), np.array([dt]),
                                       alpha[None])[:2])
            assert u.shape == u_ref.shape == (len(u),) and np.any(u != 0.0), name
            np.testing.assert_allclose(u, u_ref, rtol=1e-9, atol=1e-12, err_msg=name)
            np.testing.assert_allclose(alpha_next, alpha_ref, rtol=1e-9, atol=1e-12,
                                       err_msg=name)


def test_each_variants_status_decoding_agrees_with_its_reference_backend():
    """The role ``status`` decodes the deployed step's flags into the status the variant's
    ``reference`` backend (the oracle) reports: inside the tube and 100 units off it."""
    from stt_codegen.tube.parameters import Status

    for name, tube, stage, x in _variant_cases():
        variant = CONTROLLER_VARIANTS[name]
        function = variant.entry("casadi_step")(tube, stage)
        reference = backends.make_controller("reference", tube, stage)
        n, dt = tube.dimension, 1.0 / tube.rate_hz
        away = x.copy()
        away[:n if name != "look-ahead" else 2] += 100.0
        seen = []
        for state in (x, away):
            u, alpha_next, status = variant.entry("status")(
                function(state, 0.0, dt, np.zeros(2 * n)), dt, tube.rate_hz)
            u_ref, _, status_ref = reference.step(state, 0.0, dt, np.zeros(2 * n))
            assert status == status_ref, name
            np.testing.assert_allclose(u, u_ref, rtol=1e-9, atol=1e-12, err_msg=name)
            seen.append(status)
        assert seen[0] != Status.OUTSIDE_TUBE and seen[1] == Status.OUTSIDE_TUBE, name
