"""``stt-codegen bench drive``: the differential-drive base beside a holonomic base."""

from __future__ import annotations

import tomllib

import pytest

from stt_codegen_bench.arenas import OFFICE_CLEARANCE, OFFICE_START, OFFICE_TARGET, make_arena
from stt_codegen_bench.office_arenas import format_office_report, run_office_bench
from stt_codegen.errors import SpecError


def office_doc(seed, index, base):
    return tomllib.loads(make_arena(f"office-{base}", seed, index))


def test_offices_are_seeded_and_keep_start_and_target_free():
    a, b = office_doc(0, 3, "drive"), office_doc(0, 3, "drive")
    assert a == b and office_doc(0, 4, "drive") != a
    holonomic = office_doc(0, 3, "holonomic")
    assert holonomic["obstacles"] == a["obstacles"]        # the same office for both bases
    assert holonomic["plant"]["model"] == "single-integrator"
    for k in range(20):
        for ob in office_doc(1, k, "drive")["obstacles"]:
            for box in (OFFICE_START, OFFICE_TARGET):
                apart = any(ob["lower"][i] >= box[1][i] + OFFICE_CLEARANCE
                            or box[0][i] >= ob["upper"][i] + OFFICE_CLEARANCE
                            for i in range(2))
                assert apart, (k, ob)


def test_a_bad_base_or_count_is_refused():
    with pytest.raises(SpecError, match="kind"):
        office_doc(0, 0, "tank")
    with pytest.raises(SpecError, match="count"):
        run_office_bench(0, 0)


@pytest.mark.slow
def test_both_bases_on_two_offices_in_one_run():
    report = run_office_bench(2, 0)
    for method in ("drive", "holonomic"):
        assert report[method]["satisfied"] == 2
        assert report[method]["design_median_s"] > 0
    assert report["ratio"] == pytest.approx(report["drive"]["design_median_s"]
                                            / report["holonomic"]["design_median_s"])
    text = format_office_report(report)
    assert "| drive | 2/2 |" in text and "| holonomic | 2/2 |" in text
