"""Values that look like a unit mistake are warned about at loading (UnitWarning), never
refused; the bundled cases raise none; the command line prints one line."""

from __future__ import annotations

import tomllib
import warnings

import pytest

import stt_codegen as stt
from stt_codegen.cases import bundled_cases, bundled_spec_bytes
from stt_codegen.cli import main

BASE = tomllib.loads(bundled_spec_bytes("office-base").decode())


def _caught(data: dict) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        stt.Spec.from_dict(data)
    return [str(w.message) for w in caught if issubclass(w.category, stt.UnitWarning)]


def _with(table: str, key: str, value) -> dict:
    data = {k: (dict(v) if isinstance(v, dict) else v) for k, v in BASE.items()}
    data.setdefault(table, {})[key] = value
    return data


@pytest.mark.parametrize("case", bundled_cases())
def test_no_bundled_case_warns(case) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", stt.UnitWarning)
        stt.load_spec(case)


def test_a_rate_below_one_hertz_is_a_kilohertz_mistake() -> None:
    messages = _caught(_with("controller", "rate_hz", 0.05))
    assert messages == ["controller.rate_hz: 0.05 Hz is below 1 Hz (a rate meant in kHz? "
                        "1 kHz is 1000)"]


@pytest.mark.parametrize("key", ["track_width", "wheel_radius_error"])
def test_a_track_in_millimetres_is_named(key) -> None:
    if key == "wheel_radius_error":       # not a length: never warned about
        assert _caught(_with("plant", key, [0.01, -0.01])) == []
        return
    messages = _caught(_with("plant", key, 450.0))
    assert len(messages) == 1 and messages[0].startswith("plant.track_width: 450 is larger "
                                                         "than the state space")
    assert "millimetres" in messages[0]


def test_the_command_line_prints_one_line_and_goes_on(tmp_path, capsys) -> None:
    text = bundled_spec_bytes("omnirobot-s1").decode()
    assert text.count("rate_hz = 1000.0") == 1
    path = tmp_path / "slow.toml"
    path.write_text(text.replace("rate_hz = 1000.0", "rate_hz = 0.5"))
    code = main(["design", str(path), "--json"])
    err = capsys.readouterr().err
    assert code == 1          # the design goes on, and its own check refuses the rate
    lines = [line for line in err.splitlines() if line.startswith("warning: ")]
    assert lines == ["warning: controller.rate_hz: 0.5 Hz is below 1 Hz (a rate meant in "
                     "kHz? 1 kHz is 1000)"]
    assert "Traceback" not in err and "UnitWarning" not in err and "warnings.warn" not in err
