"""The front door takes one design object: ``generate``, ``simulate``, the plots and
``run_embedded`` take the :class:`Design` that ``design_tube`` returns (which carries its
spec), refuse anything else with a TypeError that says what to do, accept numpy inputs,
and their docstrings' examples run."""

from __future__ import annotations

import doctest
import json
import re

import numpy as np
import pytest
from conftest import design_of

import stt_codegen as stt
from stt_codegen.embedded.deploy import run_embedded

#: The functions that need a Design, called with ``what`` in the design's place.
NEEDS_A_DESIGN = {
    "generate": lambda what, tmp: stt.generate(what, tmp / "out"),
    "simulate": lambda what, tmp: stt.simulate(what, backend="casadi"),
    "plot_design": lambda what, tmp: stt.plot_design(what, tmp / "x.png"),
    "plot_run": lambda what, tmp: stt.plot_run(what, None, tmp / "x.png"),
    "run_embedded": lambda what, tmp: run_embedded(what, tmp / "build"),
}


@pytest.mark.parametrize("function", sorted(NEEDS_A_DESIGN))
@pytest.mark.parametrize("wrong", ["tube", "spec", "pair"])
def test_a_design_is_needed_and_the_error_says_how_to_get_one(function, wrong, tmp_path):
    design = design_of("omnirobot-s1")
    what = {"tube": design.tube, "spec": design.spec, "pair": (design.spec, design.tube)}[wrong]
    with pytest.raises(TypeError) as info:
        NEEDS_A_DESIGN[function](what, tmp_path)
    message = str(info.value)
    assert message.startswith(f"{function}(): parameter 'design' must be a Design, not ")
    assert "design_tube" in message
    assert list(tmp_path.iterdir()) == []          # refused before any work


def test_the_old_two_argument_calls_are_refused():
    """``generate(spec, tube, ...)`` wrote one spec's tube under another spec's name and
    hash: it now stops at the first argument. ``simulate`` has one form, the design alone
    and the rest by keyword: ``simulate(spec, design, backend="python")`` once ended in
    Python's ``got multiple values for argument 'backend'``."""
    design = design_of("omnirobot-s1")
    with pytest.raises(TypeError, match="parameter 'design' must be a Design, not Spec"):
        stt.generate(design.spec, design.tube, "out")
    with pytest.raises(TypeError, match="parameter 'design' must be a Design, not Spec"):
        stt.simulate(design.spec)
    for call in (lambda: stt.simulate(design.spec, design),
                 lambda: stt.simulate(design.spec, design, backend="python"),
                 lambda: stt.simulate(design, "python")):
        with pytest.raises(TypeError) as info:
            call()
        assert str(info.value).startswith("simulate() takes the design alone")
        assert "simulate(design, backend=..., horizon=..., seed=..., plant=...)" in \
            str(info.value)
    run = stt.simulate(design, backend="python", horizon=0.2, seed=1)
    assert run.trajectory.x.shape == (201, 3)


def test_the_spec_steps_refuse_the_wrong_kind_of_input():
    with pytest.raises(TypeError, match=r"design_tube\(\): parameter 'spec' must be a Spec, "
                                        r"not dict; for a dict use Spec.from_dict"):
        stt.design_tube({"name": "x"})
    with pytest.raises(TypeError, match=r"load_spec\(\): parameter 'spec' .* not dict; "
                                        r"for a dict use Spec.from_dict"):
        stt.load_spec({"name": "x"})
    with pytest.raises(TypeError, match="must be a Design or a Spec, not tuple"):
        stt.verify((design_of("omnirobot-s1").spec, None))


def test_generate_writes_the_designs_own_spec(tmp_path):
    """The name and the hash in the files are those of the spec the tube was designed for;
    a numpy array of language names is a sequence like any other."""
    design = design_of("omnirobot-s2")
    files = stt.generate(design, tmp_path / "s2", languages=np.array(["python"]))
    manifest = json.loads((tmp_path / "s2" / "manifest.json").read_text())
    assert manifest["spec"] == {"name": design.spec.name, "sha256": design.spec.source_hash}
    assert design.spec.name == "omnirobot-s2"
    assert [f.name for f in files] == ["manifest.json", "omnirobot_s2.py",
                                       "omnirobot_s2_vectors.json"]


def test_numpy_scalars_are_numbers():
    design = design_of("omnirobot-s1")
    plain = stt.simulate(design, backend="casadi", horizon=0.5, seed=3)
    numpy = stt.simulate(design, backend="casadi", horizon=np.float64(0.5), seed=np.int64(3))
    assert numpy.steps == plain.steps == 500
    assert np.array_equal(numpy.trajectory.x, plain.trajectory.x)
    with pytest.raises(stt.SpecError, match="horizon: must be a positive number of seconds, "
                                            "got 'soon'"):
        stt.simulate(design, horizon="soon")


@pytest.mark.slow
def test_the_plots_take_the_design(tmp_path):
    design = design_of("omnirobot-s1")
    result = stt.simulate(design, backend="casadi", horizon=1.0)
    for path in (stt.plot_design(design, tmp_path / "tube.png"),
                 stt.plot_run(design, result, tmp_path / "run.png")):
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


FRONT_DOOR = ["load_spec", "Spec.from_dict", "design_tube", "generate", "simulate", "verify",
              "plot_design", "plot_run"]


def _public(name: str):
    obj = stt
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj


@pytest.mark.parametrize("name", FRONT_DOOR)
def test_front_door_docstrings_have_every_numpydoc_section(name):
    doc = _public(name).__doc__
    for section in ("Parameters", "Returns", "Raises", "See Also", "Examples"):
        assert re.search(rf"^ *{section}\n *-{{{len(section)}}}$", doc, flags=re.M), section


def _run_examples(name: str) -> doctest.TestResults:
    finder = doctest.DocTestFinder(recurse=False)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in finder.find(_public(name), name, globs={}):
        runner.run(test)
    return runner.summarize(verbose=False)


# the two slowest (about 4 s each) in the slow tier, where test_docstrings runs every
# public example too
@pytest.mark.parametrize("name", [
    pytest.param(n, marks=pytest.mark.slow) if n in ("simulate", "plot_design") else n
    for n in FRONT_DOOR if n != "verify"])
def test_front_door_examples_run(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    results = _run_examples(name)
    assert results.attempted > 0 and results.failed == 0, name


@pytest.mark.slow
def test_verify_examples_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    results = _run_examples("verify")
    assert results.attempted > 0 and results.failed == 0
