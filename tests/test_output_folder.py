"""The output folder under concurrency, kills and builds.

* Two writers of one folder at once: both succeed, one after the other (a ``flock``
  beside the folder), and the folder is then exactly one complete generation; a writer
  that cannot get the lock in time exits 2 with one line.
* ``kill -9`` at random points of a writer: the folder is the old or the new generation,
  whole (the switch is one ``renameat2(RENAME_EXCHANGE)``; with the rename fallback a
  missing folder is restored by the next writer), and the next writer cleans up.
* ``make`` and ``cmake -S . -B build`` in a generated folder do not stop the next
  ``generate``: their products are carried over (or discarded), nothing else is.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import pickle
import random
import shutil
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from stt_codegen.cli import main
from stt_codegen.codegen import output
from stt_codegen.codegen.generate import GENERATOR, MANIFEST
from stt_codegen.codegen.output import build_products, write_generation
from stt_codegen.errors import SpecError

REPO = Path(__file__).resolve().parents[1]


def generation(tag: str, names: list[str], size: int = 2000) -> dict[str, bytes]:
    """A synthetic generation: random contents under ``tag``, and its manifest."""
    rng = random.Random(tag)
    files = {name: rng.randbytes(size) for name in names}
    files[MANIFEST] = json.dumps({"generator": GENERATOR, "tag": tag, "files": {
        n: hashlib.sha256(d).hexdigest() for n, d in sorted(files.items())}}).encode()
    return files


def content(out: Path, products: tuple = ()) -> dict[str, bytes]:
    """The folder as ``{name: bytes}``, after checking it is one complete generation:
    every entry (but ``products``) is its manifest or a file the manifest lists with its
    hash, and every listed file is there."""
    manifest = json.loads((out / MANIFEST).read_text())
    files = {p.name: p.read_bytes() for p in out.iterdir() if p.name not in products}
    assert set(files) == set(manifest["files"]) | {MANIFEST}, sorted(files)
    for name, digest in manifest["files"].items():
        assert hashlib.sha256(files[name]).hexdigest() == digest, name
    return files


def leftovers(out: Path) -> list[str]:
    """Siblings of ``out`` a writer makes (lock file, temporary and old folders)."""
    return sorted(p.name for p in out.parent.iterdir() if p.name.startswith(f".{out.name}."))


A = generation("A", [f"a{k}.c" for k in range(6)] + ["common.h"])
B = generation("B", [f"b{k}.c" for k in range(3)] + ["common.h"])


def test_two_writers_at_once_write_one_after_the_other(tmp_path):
    out = tmp_path / "out"
    for round_ in range(30):
        if round_ % 3 == 0:
            shutil.rmtree(out, ignore_errors=True)      # also race on creating the folder
        barrier = threading.Barrier(2)
        errors = []

        def write(files):
            barrier.wait()
            try:
                write_generation(out, files)
            except BaseException as exc:                 # pragma: no cover - reported below
                errors.append(exc)

        threads = [threading.Thread(target=write, args=(g,)) for g in (A, B)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert errors == []
        assert content(out) in (A, B)
        assert leftovers(out) == []


def hold_lock(out: Path):
    """Take the lock of ``out`` as a writer does; returns the open file (close to release)."""
    fh = open(out.parent / f".{out.name}.stt-codegen-lock", "a+")
    fcntl.flock(fh, fcntl.LOCK_EX)
    return fh


def test_a_writer_waits_then_gives_up_with_one_line(tmp_path, monkeypatch, capsys):
    out = tmp_path / "out"
    write_generation(out, A)
    fh = hold_lock(out)
    try:
        with pytest.raises(SpecError, match="being written by another stt-codegen process"):
            write_generation(out, B, lock_timeout=0.2)
        monkeypatch.setattr(output, "LOCK_TIMEOUT", 0.2)
        capsys.readouterr()
        assert main(["generate", "omnirobot-s1", "--lang", "python", "-o", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("error: --out") and err.count("\n") == 1, err
        assert "gave up after 0.2 s" in err
        assert content(out) == A
    finally:
        fh.close()
    # released: the next writer goes through (the lock file of the holder above is reused)
    write_generation(out, B, lock_timeout=0.2)
    assert content(out) == B and leftovers(out) == []


def test_waiting_writer_gets_the_lock_when_it_is_released(tmp_path):
    out = tmp_path / "out"
    fh = hold_lock(out)
    timer = threading.Timer(0.3, fh.close)
    timer.start()
    write_generation(out, A, lock_timeout=30)
    timer.join()
    assert content(out) == A and leftovers(out) == []


@pytest.mark.slow
def test_two_generate_processes_at_once(tmp_path):
    """The issue's reproduction: omnirobot-s1 double and omnirobot-s2 single into one folder."""
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(REPO))
    runs = [["omnirobot-s1"], ["omnirobot-s2", "--precision", "single"]]
    procs = [subprocess.Popen([sys.executable, "-m", "stt_codegen.cli", "generate", *args,
                               "-o", str(out)], env=env, stderr=subprocess.PIPE, text=True)
             for args in runs]
    results = [(p.wait(timeout=600), p.stderr.read()) for p in procs]
    assert results == [(0, ""), (0, "")]
    manifest = json.loads(content(out)[MANIFEST])
    assert manifest["spec"]["name"] in ("omnirobot-s1", "omnirobot-s2")
    assert leftovers(out) == []


CHILD = """
import pickle, sys
from stt_codegen.codegen import output
gens = pickle.load(open(sys.argv[2], "rb"))
if sys.argv[3] == "rename":
    output._exchange = lambda a, b: False        # the fallback of systems without exchange
print("ready", flush=True)
k = 1
while True:
    output.write_generation(sys.argv[1], gens[k % 2])
    k += 1
"""


@pytest.mark.slow
@pytest.mark.parametrize("switch", ["exchange", "rename"])
def test_kill_at_random_points_leaves_old_or_new(tmp_path, switch):
    """A writer alternating between two generations is killed with SIGKILL after a random
    delay (seeded), 10 times: the folder is one of them, whole, and the next writer
    recovers and cleans up."""
    big_a = generation("A", [f"a{k}.c" for k in range(12)] + ["common.h"], size=200_000)
    big_b = generation("B", [f"b{k}.c" for k in range(5)] + ["common.h"], size=200_000)
    gens = tmp_path / "gens.pickle"
    gens.write_bytes(pickle.dumps([big_a, big_b]))
    out = tmp_path / "out"
    write_generation(out, big_a)
    rng = random.Random(23)
    env = dict(os.environ, PYTHONPATH=str(REPO))
    left_something = 0
    for trial in range(10):
        child = subprocess.Popen([sys.executable, "-c", CHILD, str(out), str(gens), switch],
                                 env=env, stdout=subprocess.PIPE, text=True)
        assert child.stdout.readline() == "ready\n"
        try:
            child.wait(timeout=rng.uniform(0.01, 0.5))
        except subprocess.TimeoutExpired:
            pass
        assert child.poll() is None, "the writer stopped by itself"
        child.send_signal(signal.SIGKILL)
        child.wait()
        child.stdout.close()
        left = leftovers(out)
        left_something += bool(left)
        if out.exists():
            assert content(out) in (big_a, big_b), trial
        else:                       # killed between the fallback's two renames
            assert switch == "rename"
            olds = [n for n in left if ".stt-codegen-old-" in n]
            assert len(olds) == 1 and content(out.parent / olds[0]) in (big_a, big_b)
        final = (big_a, big_b)[trial % 2]
        write_generation(out, final)
        assert content(out) == final and leftovers(out) == [], trial
    assert left_something >= 1      # some kills did land inside a write


def test_products_of_the_generated_build_files():
    names = ["Makefile", "CMakeLists.txt", "p.c", "p.h", "p_selftest.c", "manifest.json"]
    assert build_products(names) == {"p.o": "file", "p_selftest": "file", "build": "dir"}
    assert build_products(["p.py", "p_vectors.json"]) == {}
    assert build_products(["CMakeLists.txt", "p.c", "p_selftest.c"]) == {"build": "dir"}


def test_files_named_like_products_are_foreign_without_the_build_files(tmp_path, capsys):
    out = tmp_path / "out"
    c_like = generation("C", ["p.c", "p.h", "p_selftest.c"])      # no Makefile, no CMake
    write_generation(out, c_like)
    for name, make in (("p.o", "file"), ("build", "dir")):
        path = out / name
        path.mkdir() if make == "dir" else path.write_bytes(b"\x7fELF")
        with pytest.raises(SpecError, match=f"holds '{name}'"):
            write_generation(out, c_like)
        shutil.rmtree(path) if make == "dir" else path.unlink()


def test_a_build_folder_not_made_by_cmake_for_this_folder_is_refused(tmp_path):
    out = tmp_path / "out"
    files = generation("D", ["CMakeLists.txt", "p.c", "p_selftest.c"])
    write_generation(out, files)
    (out / "build").mkdir()
    with pytest.raises(SpecError, match="holds 'build'"):
        write_generation(out, files)
    (out / "build" / "CMakeCache.txt").write_text(
        f"CMAKE_HOME_DIRECTORY:INTERNAL={tmp_path / 'elsewhere'}\n")
    with pytest.raises(SpecError, match="holds 'build'"):
        write_generation(out, files)
    (out / "build" / "CMakeCache.txt").write_text(f"CMAKE_HOME_DIRECTORY:INTERNAL={out}\n")
    write_generation(out, files)
    assert (out / "build" / "CMakeCache.txt").exists()


def run(cmd, cwd):
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    return proc.stdout


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("make") is None or shutil.which("cmake") is None
                    or shutil.which("cc") is None,
                    reason="make, cmake or cc missing: install the Debian packages make cmake gcc")
def test_generate_after_make_and_cmake(tmp_path, capsys):
    out = tmp_path / "out"
    args = ["generate", "omnirobot-s1", "-o", str(out)]
    assert main(args) == 0
    run(["make"], out)
    run(["cmake", "-S", ".", "-B", "build"], out)
    run(["cmake", "--build", "build"], out)
    products = ("omnirobot_s1.o", "omnirobot_s1_selftest", "build")
    assert all((out / p).exists() for p in products)
    generated = content(out, products)
    assert main(args + ["--precision", "single"]) == 0     # was: exit 2, "holds 'omnirobot_s1.o'"
    assert content(out, products) != generated
    assert all((out / p).exists() for p in products)        # carried over ...
    assert "passed, 0 failed" in run(["make", "selftest"], out)   # ... and rebuilt
    run(["cmake", "--build", "build"], out)
    run(["ctest", "--test-dir", "build"], out)
    assert main(args + ["--lang", "python"]) == 0          # no build files: products go
    assert sorted(content(out)) == ["manifest.json", "omnirobot_s1.py",
                                    "omnirobot_s1_vectors.json"]
    assert leftovers(out) == []


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="renameat2 is Linux's")
def test_the_switch_is_one_exchange_on_linux(tmp_path):
    """On Linux the two folders are swapped in one system call (no moment without DIR)."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    (tmp_path / "a" / "x").write_text("a")
    assert output._exchange(tmp_path / "a", tmp_path / "b") is True
    assert (tmp_path / "b" / "x").read_text() == "a" and not (tmp_path / "a" / "x").exists()


def test_an_error_between_the_fallbacks_renames_puts_the_old_folder_back(tmp_path, monkeypatch):
    out = tmp_path / "out"
    write_generation(out, A)
    monkeypatch.setattr(output, "_exchange", lambda a, b: False)
    real_rename = os.rename

    def failing_second_rename(src, dst):
        if Path(dst) == out.resolve() and ".stt-codegen-tmp-" in str(src):
            raise KeyboardInterrupt
        real_rename(src, dst)
    monkeypatch.setattr(output.os, "rename", failing_second_rename)
    with pytest.raises(KeyboardInterrupt):
        write_generation(out, B)
    assert content(out) == A and leftovers(out) == []


def test_the_next_writer_restores_a_folder_left_between_the_fallbacks_renames(tmp_path,
                                                                           monkeypatch):
    """What a writer killed between ``DIR -> old`` and ``new -> DIR`` leaves: no DIR, the
    old generation in ``.DIR.stt-codegen-old-*``, the new one (maybe partial) in
    ``.DIR.stt-codegen-tmp-*``, the lock file. The next writer puts the old one back
    before anything else (here it then fails: the old generation stays)."""
    out = tmp_path / "out"
    write_generation(out, A)
    os.rename(out, tmp_path / ".out.stt-codegen-old-0123abcd")
    (tmp_path / ".out.stt-codegen-tmp-89abcdef").mkdir()
    (tmp_path / ".out.stt-codegen-tmp-89abcdef" / "b0.c").write_bytes(B["b0.c"][:100])
    (tmp_path / ".out.stt-codegen-lock").write_text("12345\n")
    (tmp_path / ".out.stt-codegen-tmp-keep").mkdir()      # not a name a writer makes

    def disk_full(path, data):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(output, "write_durably", disk_full)
    with pytest.raises(SpecError, match="No space left on device"):
        write_generation(out, B)
    assert content(out) == A and leftovers(out) == [".out.stt-codegen-tmp-keep"]
