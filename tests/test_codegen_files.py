"""Generated files: determinism, manifest, banners, safe output folder, drift check, CLI."""

from __future__ import annotations

import hashlib
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import casadi
import pytest
from codegen_helpers import files_of

from stt_codegen import __version__
from stt_codegen.cli import main
from stt_codegen.codegen.bundled import LAYOUT, drift
from stt_codegen.codegen.functions import deployed_functions
from conftest import model_of
from stt_codegen.spec.loader import load_spec

REPO = Path(__file__).resolve().parent.parent

_GEN = """
import sys
from stt_codegen.cli import main
sys.exit(main(["generate", "omnirobot-s3", "-o", sys.argv[1], "--precision", sys.argv[2]]))
"""


# generate in two processes (slow tier); the emitter's own cross-process identity is
# tests/test_emit_instructions.py's, in the fast tier
@pytest.mark.slow
@pytest.mark.parametrize("precision", ["double", "single"])
def test_byte_identical_across_processes_and_hash_seeds(precision, tmp_path):
    outs = []
    for seed in ("0", "12345"):
        out = tmp_path / f"seed{seed}"
        env = dict(os.environ, PYTHONHASHSEED=seed)
        subprocess.run([sys.executable, "-c", _GEN, str(out), precision], env=env, check=True,
                       capture_output=True)
        outs.append({p.name: p.read_bytes() for p in sorted(out.iterdir())})
    assert outs[0] == outs[1]
    assert outs[0] == files_of("omnirobot-s3", precision)


def test_manifest_and_banners():
    files = files_of("omnirobot-s1", "double")
    spec = load_spec("omnirobot-s1")
    raw = files["manifest.json"]
    data = json.loads(raw)
    assert raw == (json.dumps(data, indent=1, sort_keys=True) + "\n").encode()
    assert data["casadi_version"] == casadi.__version__ and data["toolkit_version"] == __version__
    assert data["spec"] == {"name": "omnirobot-s1", "sha256": spec.source_hash}
    assert data["options"] == {"langs": ["c", "python"], "precision": "double"}
    assert data["files"] == {k: hashlib.sha256(v).hexdigest() for k, v in files.items()
                             if k != "manifest.json"}
    for name, blob in files.items():
        text = blob.decode("ascii")
        assert "GENERATED FILE" in text[:400], name
        assert "/work" not in text and "/tmp" not in text and str(Path.home()) not in text
        assert not re.search(r"20\d\d-\d\d-\d\d", text), name
        if not name.endswith(".json"):
            assert spec.source_hash in text[:600] and casadi.__version__ in text[:600], name


def test_header_declares_only_the_api_and_source_has_no_casadi_internals():
    for precision in ("double", "single"):
        files = files_of("omnirobot-s2", precision)
        c, h = files["omnirobot_s2.c"].decode(), files["omnirobot_s2.h"].decode()
        for word in ("casadi_", "SZ_ARG", "SZ_RES", "SZ_W", "arg[", "res[", "_checkout"):
            assert word not in c and word not in h, word
        code = re.sub(r"/\*.*?\*/", "", h, flags=re.DOTALL)
        declared = re.findall(r"^\s*int (\w+)\(", code, flags=re.MULTILINE)
        assert declared == [f"omnirobot_s2_{n}" for n in ("tube", "control", "alpha_step", "step")]
        macros = re.findall(r"^#define (\w+)", code, flags=re.MULTILINE)
        assert all(m.startswith("OMNIROBOT_S2_") for m in macros), macros
        # every computation is emitted once: one body per deployed Function
        bodies = re.findall(r"^static void (body_\w+)\(", c, flags=re.MULTILINE)
        expected = [f"body_{f.name()}" for f in deployed_functions(model_of("omnirobot-s2"))]
        assert bodies == expected and len(set(bodies)) == len(bodies)
        if precision == "single":
            assert "double" not in re.sub(r"/\*.*?\*/", "", c, flags=re.DOTALL)


def test_output_folder_rules(tmp_path):
    out = tmp_path / "out"
    assert main(["generate", "omnirobot-s1", "-o", str(out), "--lang", "python"]) == 0
    assert sorted(p.name for p in out.iterdir()) == [
        "manifest.json", "omnirobot_s1.py", "omnirobot_s1_vectors.json"]
    # regenerating with other options replaces our files and removes the stale ones
    assert main(["generate", "omnirobot-s1", "-o", str(out), "--lang", "c"]) == 0
    assert "omnirobot_s1.py" not in {p.name for p in out.iterdir()}
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    (out / "notes.txt").write_text("mine")
    assert main(["generate", "omnirobot-s1", "-o", str(out)]) == 2
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.name != "notes.txt"} == before
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "main.c").write_text("int main(void){return 0;}")
    assert main(["generate", "omnirobot-s1", "-o", str(foreign)]) == 2
    assert [p.name for p in foreign.iterdir()] == ["main.c"]
    assert main(["generate", "omnirobot-s1", "-o", str(tmp_path / "no" / "such")]) == 2
    assert not (tmp_path / "no").exists()
    assert main(["generate", "omnirobot-s1", "-o", str(tmp_path / "x"), "--lang", "rust"]) == 2
    assert not (tmp_path / "x").exists()


def test_check_outside_the_repository_names_the_missing_folder(tmp_path, capsys):
    """Run where there is no ``generated/`` (not the repository's root), ``check`` says so
    and exits 2, instead of reporting every file as missing and advising ``--update``."""
    capsys.readouterr()
    assert main(["check", "--root", str(tmp_path / "generated")]) == 2
    err = capsys.readouterr().err
    assert "--root: no folder" in err and "repository's root" in err
    assert "Traceback" not in err and not (tmp_path / "generated").exists()


@pytest.mark.slow
def test_check_detects_drift(tmp_path, capsys):
    root = tmp_path / "generated"
    assert main(["check", "--root", str(root), "--update"]) == 0
    assert main(["check", "--root", str(root)]) == 0
    target = root / "omnirobot-s2" / "double" / "omnirobot_s2.h"
    target.write_text(target.read_text().replace("Prescribed time", "Prescribed  time"))
    (root / "omnirobot-s1" / "single" / "stray.txt").write_text("x")
    capsys.readouterr()
    assert main(["check", "--root", str(root)]) == 1
    out = capsys.readouterr().out
    assert "--- " in out and "+++ " in out and "-/** Prescribed  time" in out
    assert "stray.txt" in out


def test_committed_generated_folder_is_current():
    assert sorted(LAYOUT) == ["double", "single"]
    diffs = drift(REPO / "generated")
    assert diffs == [], "".join(diffs)[:3000]
