"""Support of the codegen tests (no tests here): generate, compile and load the C of a case."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from functools import lru_cache
from pathlib import Path

import numpy as np
from conftest import designed

from stt_codegen.codegen.generate import generate_files
from stt_codegen.codegen.options import Options

STRICT = ["-std=c99", "-O2", "-ffp-contract=off", "-Wall", "-Wextra", "-Wpedantic", "-Wshadow",
          "-Wconversion", "-Wdouble-promotion", "-Wcast-qual", "-Wstrict-prototypes",
          "-Wmissing-prototypes", "-Werror"]
SINGLE_EXTRA: list[str] = []
COMPILERS = [c for c in ("gcc", "clang") if shutil.which(c)]


@lru_cache(maxsize=None)
def files_of(case: str, precision: str, langs: tuple = ("c", "python")) -> dict:
    spec, design, _ = designed(case)
    return generate_files(spec, design, Options(langs, precision))


def flags(precision: str) -> list[str]:
    return STRICT + (SINGLE_EXTRA if precision == "single" else [])


def write(folder: Path, files: dict) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in files.items():
        (folder / name).write_bytes(data)
    return folder


def compile_shared(folder: Path, prefix: str, cc: str, precision: str) -> Path:
    lib = folder / f"lib{prefix}_{cc}.so"
    cmd = [cc, *flags(precision), "-fPIC", "-shared", f"{prefix}.c", "-o", lib.name, "-lm"]
    proc = subprocess.run(cmd, cwd=folder, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return lib


class CLib:
    """ctypes view of a compiled generated library."""

    def __init__(self, path: Path, prefix: str, n: int, precision: str) -> None:
        self.lib = ctypes.CDLL(str(path))
        self.n = n
        self.real = ctypes.c_double if precision == "double" else ctypes.c_float
        self.dtype = np.float64 if precision == "double" else np.float32
        p = ctypes.POINTER(self.real)
        r = self.real
        sig = {"tube": [r, p, p, p, p, p], "control": [p, r, p, p], "alpha_step": [r, r, p, p],
               "step": [p, r, r, p, p, p]}
        self.f = {}
        for name, args in sig.items():
            fn = getattr(self.lib, f"{prefix}_{name}")
            fn.argtypes, fn.restype = args, ctypes.c_int
            self.f[name] = fn

    def arr(self, values=None, size=None):
        if values is None:
            return np.zeros(size, self.dtype)
        return np.ascontiguousarray(np.asarray(values, dtype=self.dtype))

    def ptr(self, a):
        return a.ctypes.data_as(ctypes.POINTER(self.real)) if a is not None else None

    def evaluate(self, p: dict) -> dict:
        """Every function at every point: arrays with a leading point axis."""
        n, count = self.n, len(p["t"])
        out = {k: np.zeros((count, w)) for k, w in (
            ("gamma_L", n), ("gamma_U", n), ("gamma_L_dot", n), ("gamma_U_dot", n),
            ("control_u", n), ("alpha_step", 2 * n), ("u", n), ("alpha_next", 2 * n))}
        for k in ("tube_status", "control_status", "alpha_status", "status"):
            out[k] = np.zeros(count, int)
        for i in range(count):
            x, a = self.arr(p["x"][i]), self.arr(p["alpha"][i])
            t, dt = float(p["t"][i]), float(p["dt"][i])
            g = [self.arr(None, n) for _ in range(4)]
            out["tube_status"][i] = self.f["tube"](t, self.ptr(a), *[self.ptr(v) for v in g])
            for key, v in zip(("gamma_L", "gamma_U", "gamma_L_dot", "gamma_U_dot"), g):
                out[key][i] = v
            u = self.arr(None, n)
            out["control_status"][i] = self.f["control"](self.ptr(x), t, self.ptr(a), self.ptr(u))
            out["control_u"][i] = u
            nxt = self.arr(None, 2 * n)
            out["alpha_status"][i] = self.f["alpha_step"](t, dt, self.ptr(a), self.ptr(nxt))
            out["alpha_step"][i] = nxt
            u2, nxt2 = self.arr(None, n), self.arr(None, 2 * n)
            out["status"][i] = self.f["step"](self.ptr(x), t, dt, self.ptr(a), self.ptr(u2),
                                              self.ptr(nxt2))
            out["u"][i], out["alpha_next"][i] = u2, nxt2
        return out


@lru_cache(maxsize=None)
def built(case: str, precision: str, cc: str, root: str) -> CLib:
    """Generate, compile with ``cc`` and load the C of ``case`` (cached per session)."""
    spec, design, _ = designed(case)
    folder = write(Path(root) / f"{case}-{precision}-{cc}", files_of(case, precision))
    lib = compile_shared(folder, spec.c_name, cc, precision)
    return CLib(lib, spec.c_name, design.dimension, precision)


def self_test(folder: Path, prefix: str, cc: str, precision: str) -> str:
    """Build ``<prefix>.c`` and its self-test in ``folder`` with every warning an error,
    run it, assert that every check passed, and return its last line."""
    exe = folder / "selftest"
    proc = subprocess.run([cc, *flags(precision), f"{prefix}.c", f"{prefix}_selftest.c", "-o",
                           str(exe), "-lm"], cwd=folder, capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True)
    last = run.stdout.strip().splitlines()[-1]
    assert last.endswith(" passed, 0 failed") and run.returncode == 0, run.stdout[-2000:]
    return last


def misra_findings(cppcheck: str, folder: Path, prefix: str) -> list[tuple[str, str, str, str]]:
    """cppcheck's MISRA C:2012 findings on ``<prefix>.c`` in ``folder``, as ``(file, line,
    check id, source line)``; asserts that cppcheck ran and reported something."""
    proc = subprocess.run([cppcheck, "--enable=all", "--addon=misra", "--std=c99",
                           "--suppress=missingIncludeSystem", "--quiet",
                           "--template={file}:{line}:{id}", f"{prefix}.c"],
                          cwd=folder, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    findings = [line.split(":") for line in proc.stderr.splitlines() if line.count(":") >= 2]
    assert findings, "cppcheck reported nothing at all: the deviations must show up"
    return [(name, line, check, (folder / name).read_text().splitlines()[int(line) - 1])
            for name, line, check in findings]
