"""The generated code as controller backends ``c`` and ``python`` (see :mod:`stt_codegen.runtime.backends`).

:class:`CController` generates the C (double) for a design, compiles it into a shared
library with the system C compiler and loads it with ``ctypes``; builds are cached under
``$STT_CODEGEN_CACHE`` or ``~/.cache/stt-codegen`` (never the source tree), keyed by the
SHA-256 of the generated sources and the compiler command.
:class:`GeneratedPythonController` generates the Python module and imports it from memory.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import subprocess
import tempfile
import types
from pathlib import Path

import numpy as np

from ..spec.loader import NAME_PATTERN
from ..tube.parameters import TubeDesign
from ..codegen.errors import CodegenError
from ..codegen.generate import generate_files
from ..codegen.options import Options
from ..system import atomic_write, find_tool

__all__ = ["CController", "CFLAGS", "DesignSpec", "GeneratedPythonController", "build_shared", "compiler",
           "load_python_module", "load_variant_step"]

#: Flags of the shared-library build (``-ffp-contract=off``: same rounding as CasADi's VM).
CFLAGS = ("-std=c99", "-O2", "-ffp-contract=off", "-fPIC", "-shared", "-Wall", "-Wextra",
          "-Wpedantic", "-Wshadow", "-Werror")


class DesignSpec:
    """The spec attributes code generation reads (``name``, ``c_name``, ``source_hash``,
    ``delay``, ``jitter``, ``compensate_delay``), for a design without its spec (the timing
    contract's numbers are the header's text only: the step does not read them; the loops
    that run a backend predict the state themselves).

    Parameters
    ----------
    design : TubeDesign
        Its name names the files (``"stt"`` when it is not a valid spec name).
    """

    def __init__(self, design: TubeDesign) -> None:
        self.name = design.name if NAME_PATTERN.fullmatch(design.name) else "stt"
        self.c_name = self.name.replace("-", "_")
        self.source_hash = "design:" + hashlib.sha256(repr(design).encode()).hexdigest()
        self.delay = self.jitter = 0.0
        self.compensate_delay = False


def cache_dir() -> Path:
    """Folder of compiled controllers: ``$STT_CODEGEN_CACHE`` or ``~/.cache/stt-codegen``."""
    env = os.environ.get("STT_CODEGEN_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "stt-codegen"


def compiler() -> str:
    """The C compiler: ``$CC``, else the first of ``cc``, ``gcc``, ``clang`` on ``PATH``.

    Returns
    -------
    str
        The compiler's path.

    Raises
    ------
    MissingTool
        None is installed.
    """
    names = [name for name in (os.environ.get("CC"), "cc", "gcc", "clang") if name]
    return find_tool(*names, package="gcc")


def build_shared(sources: dict[str, bytes], c_file: str, cc: str | None = None,
                 extra_flags: tuple = ()) -> Path:
    """Compile ``sources[c_file]`` (with its header) into a cached shared library.

    Parameters
    ----------
    sources : dict of str to bytes
        File name to content: the C file and the headers it includes.
    c_file : str
        The key of ``sources`` to compile.
    cc : str, optional
        The C compiler; default :func:`compiler`.
    extra_flags : tuple of str, optional
        Flags after :data:`CFLAGS` (part of the cache key).

    Returns
    -------
    Path
        The library, under :func:`cache_dir`, named by the content hash.

    Raises
    ------
    CodegenError
        The compiler failed (its output is in the message).
    MissingTool
        ``cc`` not given and no C compiler installed.
    """
    cc = cc or compiler()
    cmd = [cc, *CFLAGS, *extra_flags]
    digest = hashlib.sha256(repr(cmd).encode())
    for name in sorted(sources):
        digest.update(name.encode() + b"\0" + sources[name] + b"\0")
    key = digest.hexdigest()[:32]
    lib = cache_dir() / f"{key}.so"
    if lib.exists():
        return lib
    lib.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="stt-build-") as tmp:
        for name, data in sources.items():
            Path(tmp, name).write_bytes(data)
        out = Path(tmp, "lib.so")
        proc = subprocess.run(cmd + [c_file, "-o", str(out), "-lm"], cwd=tmp,
                              capture_output=True, text=True)
        if proc.returncode != 0:
            raise CodegenError(f"{cc} failed:\n{proc.stderr}")
        atomic_write(lib, out.read_bytes())
    return lib


class CController:
    """Backend ``c``: the generated C (double), compiled and loaded with ``ctypes``.

    The step's arrays are made once per controller (one closed loop at a time: not for
    threads sharing a controller).

    Parameters
    ----------
    design : TubeDesign
        The tube and gain compiled into the generated C.
    precision : {"double", "single"}, optional
        The floating-point type of the generated C (``double`` or ``float``; its ``step``
        then takes that type).
    cc : str, optional
        The C compiler; default :func:`compiler`.

    Raises
    ------
    MissingTool
        No C compiler is installed.
    CodegenError
        The compiler failed (a :class:`~stt_codegen.errors.ToolchainError`).
    """

    name = "c"

    def __init__(self, design: TubeDesign, precision: str = "double", cc: str | None = None) -> None:
        spec = DesignSpec(design)
        files = generate_files(spec, design, Options(("c",), precision))
        prefix = spec.c_name
        sources = {k: v for k, v in files.items() if k in (f"{prefix}.c", f"{prefix}.h")}
        self.library_path = build_shared(sources, f"{prefix}.c", cc)
        self._lib = ctypes.CDLL(str(self.library_path))
        real = ctypes.c_double if precision == "double" else ctypes.c_float
        self._dtype = np.float64 if precision == "double" else np.float32
        self._real = real
        self.n = design.dimension
        ptr = ctypes.POINTER(real)
        self._step = getattr(self._lib, f"{prefix}_step")
        self._step.argtypes = [ptr, real, real, ptr, ptr, ptr]
        self._step.restype = ctypes.c_int
        self.functions = {}
        for suffix, args in (("tube", [real, ptr, ptr, ptr, ptr, ptr]),
                             ("control", [ptr, real, ptr, ptr]),
                             ("alpha_step", [real, real, ptr, ptr])):
            f = getattr(self._lib, f"{prefix}_{suffix}")
            f.argtypes, f.restype = args, ctypes.c_int
            self.functions[suffix] = f
        self.functions["step"] = self._step

    def _p(self, arr: np.ndarray):
        return arr.ctypes.data_as(ctypes.POINTER(self._real))

    def step(self, x, t, dt, alpha):
        """``(u (n,), alpha_next (2n,), status)``; see the C header."""
        if not hasattr(self, "_args"):   # the step's arrays, made once: x, alpha, u, next
            arrays = [np.zeros(size, self._dtype) for size in (self.n, 2 * self.n) * 2]
            self._args = arrays, [self._p(a) for a in arrays]
        (xs, a, u, nxt), (px, pa, pu, pn) = self._args
        xs[:] = np.reshape(x, self.n)
        a[:] = np.reshape(alpha, 2 * self.n)
        u.fill(0.0)
        nxt.fill(0.0)
        status = self._step(px, t, dt, pa, pu, pn)
        return u.astype(float), nxt.astype(float), int(status)


def load_python_module(source: bytes, name: str) -> types.ModuleType:
    """Execute generated Python source as a module (not added to ``sys.modules``).

    Parameters
    ----------
    source : bytes
        The generated module's source, ASCII.
    name : str
        The module's name.

    Returns
    -------
    types.ModuleType
        The executed module.
    """
    module = types.ModuleType(name)
    exec(compile(source.decode("ascii"), f"<generated {name}.py>", "exec"), module.__dict__)
    return module


class GeneratedPythonController:
    """Backend ``python``: the generated Python module, executed from memory.

    Parameters
    ----------
    design : TubeDesign
        The tube and gain the generated Python module is generated for.
    """

    name = "python"

    def __init__(self, design: TubeDesign) -> None:
        spec = DesignSpec(design)
        files = generate_files(spec, design, Options(("python",), "double"))
        self.module = load_python_module(files[f"{spec.c_name}.py"], spec.c_name)

    def step(self, x, t, dt, alpha):
        """``(u (n,), alpha_next (2n,), status)``; see the generated module."""
        u, alpha_next, status = self.module.step(list(np.asarray(x, float)), float(t), float(dt),
                                                 list(np.asarray(alpha, float)))
        return np.array(u), np.array(alpha_next), int(status)


def load_variant_step(files: dict[str, str], prefix: str, output_sizes: tuple[int, ...]):
    """A controller variant's generated ``<prefix>_step`` (double), compiled into the build
    cache (:func:`build_shared`) and loaded: ``(x, t, dt, alpha) -> (outputs..., code)``.

    Parameters
    ----------
    files : dict of str to str
        The variant's ``<prefix>.h`` and ``<prefix>.c``.
    prefix : str
        The C prefix of the step, ``<prefix>_step(x, t, dt, alpha, out...)``.
    output_sizes : tuple of int
        The lengths of the step's output arrays, in order (``u``, ``alpha_next``, ...).

    Returns
    -------
    callable
        Returns the output arrays (float64) and the status code; the library stays loaded
        with it.

    Raises
    ------
    MissingTool, CodegenError
        No C compiler, or it failed.
    """
    sources = {name: text.encode() for name, text in files.items()}
    handle = ctypes.CDLL(str(build_shared(sources, f"{prefix}.c")))
    entry = getattr(handle, f"{prefix}_step")
    real_p = ctypes.POINTER(ctypes.c_double)
    entry.argtypes = [real_p, ctypes.c_double, ctypes.c_double, real_p,
                      *([real_p] * len(output_sizes))]
    entry.restype = ctypes.c_int

    outputs = [np.zeros(size) for size in output_sizes]     # made once, zeroed each call
    pointers = [b.ctypes.data_as(real_p) for b in outputs]

    def call(x, t, dt, alpha):
        x, alpha = (np.ascontiguousarray(v, dtype=np.float64) for v in (x, alpha))
        for b in outputs:
            b.fill(0.0)
        code = entry(x.ctypes.data_as(real_p), t, dt, alpha.ctypes.data_as(real_p), *pointers)
        return (*(b.copy() for b in outputs), code)

    call.library = handle  # keep the library loaded with the closure
    return call
