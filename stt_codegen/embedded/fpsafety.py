"""Float32 safety of the generated single-precision controller, on the host.

:func:`adversarial_inputs` builds float32 inputs at the places where a float expression
could overflow or produce NaN: ``t`` in {0, tiny, ``t_c`` -+ ulps, ``t_c``, ``100 t_c``}
(``tanh(t / (t_c - t))`` and its derivative), every circumvent window edge and centre
-+ ulps (the bump ``exp(-k d^2 / (r^2 - d^2))``, its derivative, the smooth max/min),
``alpha`` from 0 to 1e6 and on the domain boundary ``psi + alpha = tiny`` (the adaptive
law and the Newton step), ``dt`` from 1e-6 to 1, and states at the tube's centre, inside,
on both bounds and outside.

:func:`check_host` compiles the replay program with the host ``gcc -O2`` (and optionally
with ``-fsanitize=float-divide-by-zero,float-cast-overflow,undefined``), runs it, and
reports for every input which of ``FE_OVERFLOW``/``FE_INVALID``/``FE_DIVBYZERO`` each call
raised (``P_step``; ``P_tube`` with the time derivatives) and whether an output was not
finite, plus the single-precision errors against the double reference on the inputs
where :mod:`stt_codegen.codegen.tolerance` claims a bound.
"""

from __future__ import annotations

import itertools
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from ..tube import reference as R
from ..codegen import tolerance as T
from ..codegen.generate import generate_files
from ..codegen.options import Options
from ..errors import ToolchainError
from ..spec.loader import Spec
from ..system import find_tool
from ..tube.parameters import TubeDesign
from .programs import parse_replay, replay_source

__all__ = ["adversarial_inputs", "check_host"]

FLAG_NAMES = {1: "FE_OVERFLOW", 2: "FE_INVALID", 4: "FE_DIVBYZERO"}
SANITIZE = ("-fsanitize=float-divide-by-zero,float-cast-overflow,undefined",
            "-fno-sanitize-recover=all")


def _ulps(value: float, k: int) -> float:
    v = np.float32(value)
    step = np.float32(np.inf) if k > 0 else np.float32(-np.inf)
    for _ in range(abs(k)):
        v = np.nextafter(v, step)
    return float(v)


def adversarial_times(design: TubeDesign) -> list[tuple[str, float]]:
    """Named float32 times (see the module docstring)."""
    t_c = design.prescribed_time
    out = [("0", 0.0), ("tiny", float(np.float32(1e-45))), ("1e-30", 1e-30), ("1e-7", 1e-7)]
    out += [(f"t_c{k:+d}ulp", _ulps(t_c, k)) for k in (-8, -2, -1, 0, 1, 2)]
    out += [("100 t_c", 100.0 * t_c)]
    for j, c in enumerate(design.circumvents):
        # the edges as the float code sees them: |t - m| < r with m, r rounded to float
        m32, r32 = np.float32(c.center), np.float32(c.radius)
        for name, edge in (("start", c.start), ("end", c.end), ("centre", c.center),
                           ("start32", float(m32 - r32)), ("end32", float(m32 + r32))):
            out += [(f"c{j} {name}{k:+d}ulp", _ulps(edge, k)) for k in (-3, -2, -1, 0, 1, 2, 3)]
    return [(n, float(np.float32(t))) for n, t in out]


ALPHAS = (0.0, 1e-30, 1e-6, 1e-2, 1.0, 10.0, 1e3, 1e6)
DTS = (1e-6, 1e-4, 1e-3, 1e-2, 0.1, 1.0)
STATE_E = (0.0, 0.5, -0.999, 0.999999, 1.0, -1.0, 3.0)


def adversarial_inputs(design: TubeDesign) -> dict:
    """Inputs ``x`` (N, n), ``t``, ``dt`` (N,), ``alpha`` (N, 2n) (float32 values) and
    labels ``what`` (N,).

    Parameters
    ----------
    design : TubeDesign
        The design whose adversarial times, ``alpha`` values and states near the tube's
        walls (``e`` in :data:`STATE_E`) are combined with the periods :data:`DTS`.

    Returns
    -------
    dict
        ``x`` (N, n) state units, ``t`` (N,) s, ``dt`` (N,) s, ``alpha`` (N, 2n), each
        ndarray of float32-representable values, and ``what`` (list of N str), the label of
        each input.
    """
    n = design.dimension
    rows = {"x": [], "t": [], "dt": [], "alpha": [], "what": []}
    for (tname, t), dt in itertools.product(adversarial_times(design), DTS):
        psi = R.conflict_distance(design, np.array([t]))[0]
        alphas = [(f"alpha={a:g}", np.full(2 * n, a)) for a in ALPHAS]
        # on the boundary of the adaptive law's domain: psi + alpha barely positive
        edge = np.maximum(-psi, 0.0)
        alphas.append(("alpha=-psi+", np.array([_ulps(max(v, 0.0), 1) for v in edge])))
        for aname, alpha in alphas:
            alpha = np.asarray(alpha, dtype=np.float32).astype(float)
            g_l, g_u, _, _ = R.adaptive_tube(design, np.array([t]), alpha[None, :])
            mid, half = (g_u[0] + g_l[0]) / 2, (g_u[0] - g_l[0]) / 2
            for e in STATE_E:
                x = np.float32(mid + e * half).astype(float)
                if e == 1.0:
                    x = np.float32(g_u[0]).astype(float)
                elif e == -1.0:
                    x = np.float32(g_l[0]).astype(float)
                rows["x"].append(x)
                rows["t"].append(t)
                rows["dt"].append(float(np.float32(dt)))
                rows["alpha"].append(alpha)
                rows["what"].append(f"t={tname} dt={dt:g} {aname} e={e:g}")
    return {k: (np.array(v) if k != "what" else v) for k, v in rows.items()}


def _host_cc() -> str:
    return find_tool("gcc", "cc", package="gcc")


def check_host(spec: Spec, design: TubeDesign, out_dir: Path | None = None, *,
               sanitize: bool = True, inputs: dict | None = None) -> dict:
    """Run the adversarial inputs through the single-precision C on the host.

    Parameters
    ----------
    spec : Spec
        The spec (name, dimension) of the generated code.
    design : TubeDesign
        The design compiled in single precision.
    out_dir : pathlib.Path, optional
        Folder for the generated code and the programs (created); default a new temporary
        folder.
    sanitize : bool, optional
        Also build with :data:`SANITIZE` (undefined-behaviour sanitizer) and run that.
    inputs : dict, optional
        Inputs as :func:`adversarial_inputs` returns them; default those of ``design``.

    Returns
    -------
    dict
        ``count``; ``raised``: list of ``{"what", "step", "tube", "nonfinite"}`` (flag
        names) for every input where a call raised a flag or gave a non-finite output;
        ``raised_summary``: number of inputs per (function, flag); ``sanitizer``: ``"clean"``
        or the first runtime error; ``bounded``: the error/bound ratios
        (:func:`stt_codegen.embedded.deploy.compare_outputs`) on the inputs inside the
        tube where the bound applies, and their count.

    Raises
    ------
    ToolchainError
        The host C compiler fails, or the program exits with an error.
    """
    from .deploy import compare_outputs
    out = Path(out_dir) if out_dir is not None else Path(tempfile.mkdtemp(prefix="stt-fp32-"))
    out.mkdir(parents=True, exist_ok=True)
    files = generate_files(spec, design, Options(("c",), "single"))
    for name, data in files.items():
        (out / name).write_bytes(data)
    p = inputs or adversarial_inputs(design)
    src = out / "fpsafety.c"
    src.write_text(replay_source(spec, design, p["x"], p["t"], p["dt"], p["alpha"],
                                 what="adversarial float32 inputs"))
    cc = _host_cc()
    lib = out / f"{spec.c_name}.c"
    base = [cc, "-std=c99", "-O2", "-DSTT_FENV", f"-I{out}", str(lib), str(src), "-lm"]

    def build_run(extra, exe):
        proc = subprocess.run(base[:1] + list(extra) + base[1:] + ["-o", str(exe)],
                              capture_output=True, text=True, check=False)
        if proc.returncode:
            raise ToolchainError(f"host build failed:\n{proc.stderr}")
        return subprocess.run([str(exe)], capture_output=True, text=True, check=False,
                              timeout=600)

    run = build_run((), out / "fpsafety")
    if run.returncode:
        raise ToolchainError(f"fpsafety exited with {run.returncode}:\n{run.stderr[-2000:]}")
    res = parse_replay(run.stdout, spec.dimension)
    raised, summary = [], {}
    for k, (fs, ft) in enumerate(res.flags):
        if fs or ft or res.nonfinite[k]:
            entry = {"what": p["what"][k],
                     "step": [v for b, v in FLAG_NAMES.items() if fs & b],
                     "tube": [v for b, v in FLAG_NAMES.items() if ft & b],
                     "nonfinite": bool(res.nonfinite[k])}
            raised.append(entry)
            for fn in ("step", "tube"):
                for flag in entry[fn]:
                    summary[f"{fn} {flag}"] = summary.get(f"{fn} {flag}", 0) + 1
            if entry["nonfinite"]:
                summary["nonfinite output"] = summary.get("nonfinite output", 0) + 1
    sanitizer = "not run"
    if sanitize:
        srun = build_run(SANITIZE, out / "fpsafety_ubsan")
        sanitizer = "clean" if srun.returncode == 0 and "runtime error" not in srun.stderr \
            else srun.stderr.strip().splitlines()[0] if srun.stderr.strip() \
            else f"exit {srun.returncode}"
    # where the tolerance bound applies: t in [0, 1.2 t_c], psi + alpha > 0, state inside
    # the tube with a status rounding cannot change, tube at least 1e-2 wide
    x, t, dt, alpha = p["x"], p["t"], p["dt"], p["alpha"]
    g_l, g_u, _, _ = R.adaptive_tube(design, t, alpha)
    psi = R.conflict_distance(design, t)
    e = (2 * x - (g_u + g_l)) / np.maximum(g_u - g_l, 1e-300)
    ok = ((t >= 0) & (t <= 1.2 * design.prescribed_time) & np.all(psi + alpha > 0, axis=1)
          & np.all(g_u - g_l >= 1e-2, axis=1) & np.all(np.abs(e) < 1, axis=1)
          & T.status_certain(design, x, alpha, g_l, g_u, T.UNIT_SINGLE))
    idx = np.flatnonzero(ok)
    sub = type(res)(res.status[idx], res.u[idx], res.alpha_next[idx], res.gamma_L[idx],
                    res.gamma_U[idx], None, None, None)
    bounded = compare_outputs(design, x[idx], t[idx], dt[idx], alpha[idx], sub)
    bounded["count"] = int(idx.size)
    return {"count": len(p["t"]), "raised": raised, "raised_summary": summary,
            "sanitizer": sanitizer, "bounded": bounded, "build_dir": str(out)}
