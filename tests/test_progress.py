"""Progress of long work: ``design_tube`` and ``verify`` report Progress events with
fractions that never decrease and end at 1; the command line draws them as a bar on a
terminal only."""

from __future__ import annotations

import argparse
import io
import subprocess
import sys

import pytest

import stt_codegen as stt
from stt_codegen.cli import common
from stt_codegen.design.cascade_gain import _second_stage
from stt_codegen.design.certificate.cascade_sampled import cascade_check_of
from stt_codegen.progress import Progress, report, reporting


def _fractions_rise_to_one(events: list[Progress]) -> None:
    fractions = [e.fraction for e in events]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0
    assert all(0.0 <= f <= 1.0 for f in fractions)
    assert events[-1].stage == "done"


@pytest.mark.parametrize("name, stages", [
    ("omnirobot-s1", {"reach tube", "candidate tubes"}),          # law (13), the paper's search
    ("second-order-s1", {"candidate tubes", "via points", "cascade stage",
                         "cascade certificate"}),                               # the cascade
])
def test_design_reports_its_stages_with_rising_fractions(name, stages):
    # The cascade's stage and its certificate are computed once per process; a test run
    # earlier in this worker may have designed the same spec, and then the stage is not
    # computed (nor reported) again. Clear both so that this design does the work.
    _second_stage.cache_clear()
    cascade_check_of.cache_clear()
    events: list[Progress] = []
    design = stt.design_tube(stt.load_spec(name), progress=events.append)
    assert design == stt.design_tube(stt.load_spec(name))    # the callback changes nothing
    _fractions_rise_to_one(events)
    assert stages <= {e.stage for e in events}
    assert len({e.fraction for e in events}) >= 3             # it moves on the way
    assert all(isinstance(e, Progress) and str(e) == e.message for e in events)


@pytest.mark.slow
def test_verify_reports_the_same_events():
    events: list[Progress] = []
    stt.verify(stt.design_tube(stt.load_spec("omnirobot-s1")), progress=events.append)
    _fractions_rise_to_one(events)
    assert all(e.message.startswith(e.stage + " (") for e in events)   # "lemma 3.3 (3/10)"


def test_a_nested_block_reports_into_its_share():
    events: list[Progress] = []
    with reporting(events.append, final="done"):
        report("a", 0.5)
        with reporting(None, (0.6, 0.8)):
            report("b", 0.5)
            report("c", 0.1)                   # behind the last: held at it
    report("outside", 0.9)                     # no receiver: nothing
    assert [(e.stage, round(e.fraction, 12)) for e in events] == [
        ("a", 0.5), ("b", 0.7), ("c", 0.7), ("done", 1.0)]


class _Stderr(io.StringIO):
    def __init__(self, tty: bool) -> None:
        super().__init__()
        self.tty = tty

    def isatty(self) -> bool:
        return self.tty


@pytest.mark.parametrize("tty, quiet, drawn", [(True, False, True), (True, True, False),
                                               (False, False, False)])
def test_the_bar_is_drawn_on_a_terminal_without_quiet_only(monkeypatch, tty, quiet, drawn):
    stderr = _Stderr(tty)
    monkeypatch.setattr(sys, "stderr", stderr)
    monkeypatch.setattr(common, "BAR_DELAY", 0.0)
    with common.progress_bar(argparse.Namespace(quiet=quiet), "design") as progress:
        assert (progress is not None) == drawn
        if progress is not None:
            progress(Progress("candidate tubes", 0.25, "candidate tube 2 of at most 40"))
    text = stderr.getvalue()
    assert ("design:  25%" in text and "candidate tube 2 of at most 40" in text) == drawn
    assert (text == "") == (not drawn)


@pytest.mark.slow
def test_the_commands_print_no_progress_when_stderr_is_not_a_terminal(tmp_path):
    for command in (["design", "second-order-s1"], ["verify", "omnirobot-s1"]):
        out = subprocess.run([sys.executable, "-m", "stt_codegen.cli", *command],
                             capture_output=True, text=True, timeout=900, cwd=tmp_path)
        assert out.returncode == 0 and out.stderr == "", out.stderr
        assert "%|" not in out.stdout


def test_a_second_order_design_shows_its_progress_on_a_terminal(monkeypatch, capsys):
    """The command itself, on a terminal (stderr a tty; the bar's 2 s delay off): the bar
    is drawn from the design's own events, up to 100 %."""
    from stt_codegen.cli import main
    stderr = _Stderr(True)
    monkeypatch.setattr(sys, "stderr", stderr)
    monkeypatch.setattr(common, "BAR_DELAY", 0.0)
    assert main(["design", "second-order-s1"]) == 0
    text = stderr.getvalue()
    assert "design:" in text and "100%" in text
    assert "cascade" in text.lower() or "candidate" in text.lower()
    assert "%|" not in capsys.readouterr().out          # standard output stays clean
