"""Subcommand ``design`` (arguments from :func:`configure_design`): design and certify only."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def cmd_design(args: argparse.Namespace) -> int:
    """``stt-codegen design SPEC [--json] [--plot PNG] [--dims I,J]``: 0 designed, 1 no
    design (``--plot``: the best rejected tube is drawn), 2 bad input."""
    from ..system import atomic_write
    from ..errors import DesignError, SpecError
    from ..spec.loader import load_spec
    from .search import design_tube
    if args.plot and not Path(args.plot).parent.is_dir():
        raise SpecError("--plot", f"folder {str(Path(args.plot).parent)!r} does not exist")
    spec = load_spec(args.spec)
    if args.plot or args.dims is not None:
        from ..runtime.plots import parse_dims
        dims = parse_dims(args.dims, spec.dimension)
    try:
        design = design_tube(spec)
    except DesignError as exc:
        if args.json:
            print(json.dumps({"spec": spec.name, "designed": False, "reason": str(exc)},
                             indent=2, sort_keys=True))
        if args.plot:
            _plot_rejected(spec, exc, Path(args.plot), dims)
        raise
    if args.plot:
        from ..runtime.plots import plot_design
        atomic_write(Path(args.plot), lambda tmp: plot_design(spec, design, tmp, dims=dims))
    if args.json:
        print(json.dumps(design.to_json(spec.name), indent=2, sort_keys=True))
        return 0
    tube = design.tube
    print(f"{spec.name}: designed with the {design.method} method in "
          f"{design.design_time_s * 1e3:.1f} ms, gain k = {tube.gain:.4g}, "
          f"{len(tube.segments)} reach segment(s), {len(tube.circumvents)} circumvent(s)")
    for c in tube.circumvents:
        print(f"  circumvent obstacle {c.obstacle}: x{c.dimension + 1} {c.side}, window "
              f"[{c.start:.3f}, {c.end:.3f}] s, height {c.height:.3g}, sharpness {c.sharpness:g}")
    for s in tube.segments:
        box = ", ".join(f"[{a:.3g}, {b:.3g}]" for a, b in zip(s.lower_to, s.upper_to))
        print(f"  reach segment {s.profile} [{s.start:.3f}, {s.end:.3f}] s to {box}")
    for m in design.certificate.margins:
        print(f"  {'PASS' if m.passed else 'FAIL'}  {m.name}: margin {m.margin:.4g}")
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


def _plot_rejected(spec, error, path: Path, dims: tuple[int, int]) -> None:
    """Write the plot of the best rejected tube to ``path``, or say why there is none."""
    from ..runtime.plots import plot_rejected
    from ..system import atomic_write
    if error.tried is None:
        print(f"no plot written to {path}: no tube was tried", file=sys.stderr)
        return
    atomic_write(path, lambda tmp: plot_rejected(spec, error, tmp, dims=dims))
    print(f"plot written to {path}: it shows the best rejected tube", file=sys.stderr)


def configure_design(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen design``."""
    p.add_argument("spec", metavar="SPEC", help="bundled case name or spec file")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="PNG", help="write a figure of the designed tube (of "
                   "the best rejected tube when there is no design)")
    p.add_argument("--dims", metavar="I,J", help="state dimensions of the plot's arena, "
                   "zero-based (default: 0,1)")
    p.set_defaults(handler=cmd_design)
