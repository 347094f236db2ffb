"""The spec's numbers live in const tables: a one-number change is a one-line change."""

from __future__ import annotations

import difflib
from importlib.resources import files

from stt_codegen.codegen.generate import generate_files
from stt_codegen.codegen.options import Options
from stt_codegen.design.search import design_tube
from stt_codegen.spec.loader import load_spec


def _generate(path):
    spec = load_spec(str(path))
    design = design_tube(spec).tube
    return generate_files(spec, design, Options(("c", "python"), "double"))


def _changed(a: bytes, b: bytes) -> list[str]:
    return [line for line in difflib.unified_diff(a.decode().splitlines(), b.decode().splitlines(),
                                                  lineterm="", n=0)
            if line[:1] in "+-" and not line.startswith(("+++", "---"))]


def test_kappa_change_touches_at_most_ten_lines(tmp_path):
    source = files("stt_codegen.cases").joinpath("omnirobot-s1.toml").read_text()
    assert "\nkappa = 5.0\n" in source
    (tmp_path / "omnirobot-s1.toml").write_text(source)
    (tmp_path / "k4").mkdir()
    (tmp_path / "k4" / "omnirobot-s1.toml").write_text(source.replace("\nkappa = 5.0\n",
                                                                      "\nkappa = 4.0\n"))
    before = _generate(tmp_path / "omnirobot-s1.toml")
    after = _generate(tmp_path / "k4" / "omnirobot-s1.toml")
    for name in ("omnirobot_s1.c", "omnirobot_s1.h", "omnirobot_s1.py"):
        changed = _changed(before[name], after[name])
        assert 0 < len(changed) <= 10, (name, len(changed), changed[:20])
    # the new value is in the table, once per language
    assert sum("4.0, /* kappa */" in line for line in _changed(before["omnirobot_s1.c"],
                                                               after["omnirobot_s1.c"])) == 1
    assert any(line.startswith("+KAPPA = 4.0") for line in _changed(before["omnirobot_s1.py"],
                                                                    after["omnirobot_s1.py"]))
