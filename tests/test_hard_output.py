"""``generate -o DIR``: never writes outside DIR, never overwrites files it did not generate.

Each hostile layout is checked through the command line (exit 2, one ``error:`` line)
and by comparing every file under the test folder before and after: nothing outside
DIR changes, and in a refused DIR nothing changes either.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest

from stt_codegen.cli import main
from stt_codegen.errors import SpecError
from stt_codegen.codegen.output import write_generation

ARGS = ["generate", "omnirobot-s1", "--lang", "python"]


def snapshot(root: Path) -> dict[str, tuple]:
    """Every path under ``root`` (not following symlinks): kind and content."""
    out = {}
    for folder, dirs, files in os.walk(root, followlinks=False):
        for name in dirs + files:
            p = Path(folder, name)
            rel = str(p.relative_to(root))
            if p.is_symlink():
                out[rel] = ("link", os.readlink(p))
            elif p.is_dir():
                out[rel] = ("dir",)
            else:
                out[rel] = ("file", hashlib.sha256(p.read_bytes()).hexdigest())
    return out


@pytest.fixture
def arena(tmp_path):
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "keep.txt").write_text("precious")
    (outside / "omnirobot_s1.py").write_text("not generated")
    return tmp_path, outside


def refused(capsys, out: Path) -> None:
    capsys.readouterr()
    assert main(ARGS + ["-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --out") and err.count("\n") == 1, err


def fresh(out: Path) -> dict:
    assert main(ARGS + ["-o", str(out)]) == 0
    return json.loads((out / "manifest.json").read_text())


def test_manifest_naming_paths_outside_is_refused(arena, capsys):
    root, outside = arena
    out = root / "out"
    out.mkdir()
    for name in ("../outside/keep.txt", str(outside / "keep.txt"), "..", ".hidden", "a\\b"):
        (out / "manifest.json").write_text(json.dumps(
            {"generator": "stt-codegen", "files": {name: "0" * 64}}))
        before = snapshot(root)
        refused(capsys, out)
        assert snapshot(root) == before, name


def test_crafted_manifest_with_stale_entry_cannot_delete_outside(arena, capsys):
    """The previous generation's stale files are removed only if they are entries of DIR."""
    root, outside = arena
    out = root / "out"
    manifest = fresh(out)
    manifest["files"]["gone.txt"] = "0" * 64           # listed, not present: harmless
    (out / "manifest.json").write_text(json.dumps(manifest))
    assert main(ARGS + ["-o", str(out)]) == 0
    assert (outside / "keep.txt").read_text() == "precious"


@pytest.mark.parametrize("target", ["keep.txt", "omnirobot_s1.py", "."])
def test_symlink_inside_pointing_out_is_refused(arena, capsys, target):
    root, outside = arena
    out = root / "out"
    fresh(out)
    link = out / ("omnirobot_s1.py" if target != "." else "sub")
    link.unlink(missing_ok=True)
    link.symlink_to(outside / target if target != "." else outside)
    before = snapshot(root)
    refused(capsys, out)
    assert snapshot(root) == before


def test_symlinked_manifest_is_refused(arena, capsys):
    root, outside = arena
    out = root / "out"
    manifest = fresh(out)
    (outside / "manifest.json").write_text(json.dumps(manifest))
    (out / "manifest.json").unlink()
    (out / "manifest.json").symlink_to(outside / "manifest.json")
    before = snapshot(root)
    refused(capsys, out)
    assert snapshot(root) == before


def test_existing_file_or_dangling_link_in_place_of_the_folder(arena, capsys):
    root, outside = arena
    (root / "afile").write_text("x")
    (root / "dangling").symlink_to(root / "nowhere")
    before = snapshot(root)
    refused(capsys, root / "afile")
    refused(capsys, root / "dangling")
    refused(capsys, root / "afile" / "sub")
    assert snapshot(root) == before


def test_edited_generated_file_is_not_overwritten(arena, capsys):
    root, _ = arena
    out = root / "out"
    fresh(out)
    (out / "omnirobot_s1.py").write_text("# my edits\n")
    (out / "sub").mkdir()
    before = snapshot(root)
    refused(capsys, out)                               # a folder inside
    (out / "sub").rmdir()
    before = snapshot(root)
    refused(capsys, out)                               # the edited file
    assert snapshot(root) == before
    (out / "omnirobot_s1.py").unlink()                 # moved away: regenerates
    assert main(ARGS + ["-o", str(out)]) == 0


def test_dotdot_in_the_folder_path_stays_in_that_folder(arena):
    root, outside = arena
    (root / "a").mkdir()
    before = snapshot(outside)
    assert main(ARGS + ["-o", str(root / "a" / ".." / "b")]) == 0
    assert (root / "b" / "manifest.json").is_file()
    assert snapshot(outside) == before


@pytest.mark.parametrize("name", ["../x", "/abs", "", ".", "..", ".hidden", "a/b", "a\\b",
                                  "nul\0"])
def test_unsafe_generated_names_are_refused(tmp_path, name):
    with pytest.raises(SpecError) as info:
        write_generation(tmp_path / "out", {name: b"x"})
    assert info.value.field == "out_dir"
    assert not (tmp_path / "out").exists() and not (tmp_path / "x").exists()


def test_check_update_replaces_edited_generated_files(tmp_path):
    """``check --update`` on a version-controlled tree may overwrite hand edits."""
    files = {"a.txt": b"1", "manifest.json": b""}
    from stt_codegen.codegen.generate import GENERATOR
    files["manifest.json"] = json.dumps({"generator": GENERATOR, "files": {
        "a.txt": hashlib.sha256(b"1").hexdigest()}}).encode()
    out = tmp_path / "g"
    write_generation(out, files)
    (out / "a.txt").write_text("edited")
    with pytest.raises(Exception):
        write_generation(out, files)
    write_generation(out, files, replace_edited=True)
    assert (out / "a.txt").read_text() == "1"
