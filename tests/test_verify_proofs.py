"""The proof cache of ``verify`` (stt_codegen.proofs.design_independent) and the ``verify`` function.

A cached run must give the report an uncached run gives; a corrupt or stale entry is
ignored; a changed piece, proof module or library version misses the cache; every piece
printed while proving is in the key.
"""

from __future__ import annotations

import json
import subprocess
import sys

import casadi as ca
import pytest
import sympy as sp

import stt_codegen.cli.verify as verify_command_line
from stt_codegen.design.search import design_tube
from stt_codegen.spec.loader import load_spec
from stt_codegen.tube import pieces
from stt_codegen.proofs import deployed, design_independent as proofs
from stt_codegen.proofs.check import Check
from stt_codegen.verification.command import verify


@pytest.fixture(autouse=True)
def cache_home(tmp_path, monkeypatch):
    """A fresh cache directory and no proofs remembered in this process."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    monkeypatch.setattr(proofs, "_IN_PROCESS", {})
    return tmp_path / "cache" / "stt-codegen"


def _stub(calls: list) -> callable:
    """A stand-in for :func:`proofs.prove` that counts its calls."""
    def prove(max_n=3, progress=None):
        calls.append(max_n)
        forms = {"reach_rate": True, "bump_rate": True,
                 "adaptive_law": {"trigger": "t", "trigger_positive": True,
                                  "upper_bound_proved": True, "df_da": "d"}}
        return proofs.Proofs((Check("stub", True, "stub proof", {"n": max_n}),), forms)
    return prove


def test_an_entry_is_written_then_read_instead_of_proving(cache_home, monkeypatch):
    calls: list = []
    monkeypatch.setattr(proofs, "prove", _stub(calls))
    first = proofs.design_independent_proofs(2)
    assert calls == [2] and not first.from_cache
    files = list(cache_home.iterdir())
    assert [f.name for f in files] == [f"proofs-{proofs.proof_key(2)}.json"]
    monkeypatch.setattr(proofs, "_IN_PROCESS", {})
    second = proofs.design_independent_proofs(2)
    assert calls == [2] and second.from_cache and second == first


@pytest.mark.parametrize("content", [
    "", "{", "not json", "[]", '{"format": 1}', "\xff\xfe",
    None,   # a valid entry with one field of the wrong type
])
def test_a_corrupt_entry_is_ignored_and_proved_again(content, cache_home, monkeypatch):
    calls: list = []
    monkeypatch.setattr(proofs, "prove", _stub(calls))
    key = proofs.proof_key(2)
    path = cache_home / f"proofs-{key}.json"
    cache_home.mkdir(parents=True)
    if content is None:
        good = {"format": proofs.CACHE_FORMAT, "key": key, **_stub([])(2).to_json()}
        good["forms"]["bump_rate"] = "yes"
        content = json.dumps(good)
    path.write_bytes(content.encode("latin-1"))
    assert proofs.load_cached(key) is None
    got = proofs.design_independent_proofs(2)
    assert calls == [2] and not got.from_cache
    assert proofs.load_cached(key) == got           # overwritten with a valid entry


def test_an_entry_under_another_key_or_format_is_not_read(cache_home, monkeypatch):
    monkeypatch.setattr(proofs, "prove", _stub([]))
    key = proofs.proof_key(2)
    proofs.store(key, proofs.prove(2))
    path = cache_home / f"proofs-{key}.json"
    entry = json.loads(path.read_text())
    assert proofs.load_cached(key) is not None
    for field, value in (("key", "0" * 64), ("format", proofs.CACHE_FORMAT + 1)):
        path.write_text(json.dumps({**entry, field: value}))
        assert proofs.load_cached(key) is None, field


def test_an_unwritable_cache_costs_time_only(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    monkeypatch.setattr(proofs, "prove", _stub([]))
    assert not proofs.store("k", proofs.prove(2))
    assert proofs.design_independent_proofs(2).checks[0].name == "stub"
    assert list(tmp_path.iterdir()) == [blocker]


def test_an_unreadable_proof_source_means_no_cache(cache_home, tmp_path, monkeypatch):
    calls: list = []
    monkeypatch.setattr(proofs, "prove", _stub(calls))
    monkeypatch.setattr(proofs.lemma, "__file__", str(tmp_path / "missing.py"))
    proofs.design_independent_proofs(2)
    proofs.design_independent_proofs(2)
    assert calls == [2, 2] and not cache_home.exists()


def _bump_linear_exponent(rates: bool = True) -> ca.Function:
    """The bump with ``-k |d| / den`` for ``-k d^2 / den`` in the exponent."""
    names = ["t", "start", "end", "center", "radius", "sharpness", "height"]
    t, start, end, center, radius, sharpness, height = (ca.SX.sym(n) for n in names)
    d = t - center
    inside = ca.logic_and(ca.logic_and(t > start, t < end), ca.fabs(d) < radius)
    denom = ca.if_else(inside, (radius - ca.fabs(d)) * (radius + ca.fabs(d)), 1.0)
    exponent = ca.fmax(-sharpness * ca.fabs(d) / denom, -pieces.EXP_ARGUMENT_BOUND)
    y = ca.if_else(inside, height * ca.exp(exponent), 0.0)
    return ca.Function("bump", [t, start, end, center, radius, sharpness, height],
                       [y, ca.jacobian(y, t)], names, ["y", "y_dot"])


def test_a_changed_piece_misses_the_cache(monkeypatch):
    key = proofs.proof_key(3)
    assert proofs.proof_key(3) == key                  # deterministic
    monkeypatch.setattr(pieces, "bump", _bump_linear_exponent)
    assert proofs.proof_key(3) != key


def test_a_changed_proof_library_or_dimension_misses_the_cache(monkeypatch, tmp_path):
    key = proofs.proof_key(3)
    assert proofs.proof_key(2) != key
    monkeypatch.setattr(sp, "__version__", sp.__version__ + ".post1")
    assert proofs.proof_key(3) != key
    monkeypatch.undo()
    changed = tmp_path / "lemma.py"
    changed.write_bytes(proofs.Path(proofs.lemma.__file__).read_bytes() + b"\n# changed\n")
    monkeypatch.setattr(proofs.lemma, "__file__", str(changed))
    assert proofs.proof_key(3) != key


def test_verify_takes_a_design_or_a_spec_only():
    spec = load_spec("omnirobot-s1")
    with pytest.raises(TypeError, match="Design or a Spec"):
        verify((spec, None))


@pytest.mark.slow
def test_a_cached_report_is_the_uncached_report(cache_home):
    """Same names, statuses, evidence and data, with the proofs proved, written, read."""
    spec = load_spec("omnirobot-s1")
    design = design_tube(spec)
    stages: list[str] = []
    fresh = verify(design, cache=False, progress=lambda event: stages.append(event.message))
    assert not cache_home.exists()                          # cache=False touches no file
    assert stages[0] == "deployed pieces (1/9)" and stages[-2] == "sampled loop (9/9)"
    assert stages[-1] == "done (9/9)"
    written = verify(design)                                # proves, writes the entry
    proofs._IN_PROCESS.clear()
    stages.clear()
    cached = verify(spec, progress=lambda event: stages.append(event.message))  # reads it
    assert "cached proofs (5/10)" in stages and "lemma 3.3 (3/10)" not in stages
    for report in (written, cached):
        assert [(c.name, c.passed, c.detail, c.data) for c in report.checks] == [
            (c.name, c.passed, c.detail, c.data) for c in fresh.checks]
    assert fresh.passed and len(list(cache_home.iterdir())) == 1


@pytest.mark.slow
def test_every_printed_piece_is_in_the_key(monkeypatch):
    """The key lists every CasADi Function the proofs print: proving with the printing
    recorded finds no other."""
    printed: set[str] = set()
    original = deployed.sympy_expressions

    def record(function, inputs):
        printed.add(function.serialize())
        return original(function, inputs)

    for name in dir(deployed):
        getattr(getattr(deployed, name), "cache_clear", lambda: None)()
    monkeypatch.setattr(deployed, "sympy_expressions", record)
    proofs.prove(3)
    listed = {f.serialize() for f in deployed.proved_pieces(3).values()}
    assert printed and printed <= listed, len(printed - listed)
    for name in dir(deployed):
        getattr(getattr(deployed, name), "cache_clear", lambda: None)()


@pytest.mark.parametrize("first", ["import stt_codegen.proofs.lemma", "import stt_codegen",
                                   "from stt_codegen.proofs import Check",
                                   "import stt_codegen.verification.command"])
def test_stt_codegen_verify_is_the_function_whatever_is_imported_first(first):
    """No module is named ``stt_codegen.verify``: the name is only the front door's
    function, whatever is imported first."""
    code = (f"{first}\nimport importlib.util, stt_codegen, stt_codegen.proofs.design_independent\n"
            "from stt_codegen.verification.command import verify\n"
            "assert stt_codegen.verify is verify, stt_codegen.verify\n"
            "from stt_codegen import verify as again\nassert again is verify\n"
            "assert importlib.util.find_spec('stt_codegen.verify') is None")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=False)
    assert run.returncode == 0, run.stderr


def test_importing_stt_codegen_stays_cheap():
    code = "import sys, stt_codegen\nassert 'sympy' not in sys.modules and 'numpy' not in sys.modules"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=False)
    assert run.returncode == 0, run.stderr
