"""``stt-codegen demo``: every bundled case generated, compiled and run in closed loop."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..system import atomic_write
from .common import add_backend_argument, design_spec
from .plotting import add_dims_argument, plot_dims
from .simulate import SUMMARY_HEADER, summary_line

__all__ = ["cmd_demo", "configure_demo"]


def cmd_demo(args: argparse.Namespace) -> int:
    """0 every case satisfied, 1 otherwise, 3 toolchain.

    Parameters
    ----------
    args : argparse.Namespace
        ``out`` (the folder for code and plots, created), ``backend`` and ``dims``.

    Returns
    -------
    int
        0 every bundled case satisfied, 1 otherwise.

    Raises
    ------
    ToolchainError
        A compiler is missing or fails (exit code 3).
    SpecError
        ``--dims`` is not two distinct dimensions of a case (exit code 2).
    """
    from ..cases import bundled_cases
    from ..codegen.api import generate
    from ..runtime.plots import plot_run
    from ..runtime.simulate import simulate
    from ..spec.loader import load_spec
    specs = {name: load_spec(name) for name in bundled_cases()}
    dims = {name: plot_dims(args, spec) for name, spec in specs.items()}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"For every bundled case: design the tube, generate the C and Python controllers "
          f"into {out}/<case>/, and run the {args.backend} controller in closed loop.")
    print(SUMMARY_HEADER)
    all_ok = True
    for name, spec in specs.items():
        design = design_spec(spec, args)
        generate(design, out / name)
        result = simulate(design, backend=args.backend)   # the cascade's for second order
        atomic_write(out / f"{name}.png",
                     lambda tmp: plot_run(design, result, tmp, dims=dims[name]))
        print(summary_line(result), flush=True)
        all_ok &= result.satisfied
    print(f"generated code in {out}/<case>/, plots in {out}/<case>.png")
    return 0 if all_ok else 1


def configure_demo(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen demo``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``--out``, ``--backend``, ``--dims`` and the ``handler``
        :func:`cmd_demo`.
    """
    p.add_argument("--out", default="stt-demo", metavar="DIR",
                   help="folder for the generated code and the plots (default: %(default)s)")
    add_backend_argument(p)
    add_dims_argument(p)
    p.set_defaults(handler=cmd_demo)
