"""Subcommand ``design`` (arguments from :func:`configure_design`): design and certify only."""

from __future__ import annotations

import argparse
import json
from pathlib import Path


def cmd_design(args: argparse.Namespace) -> int:
    """``stt-codegen design SPEC [--json] [--plot PNG]``: 0 designed, 1 no design, 2 bad input."""
    from ..system import atomic_write
    from ..errors import DesignError, SpecError
    from ..spec.loader import load_spec
    from .search import design_tube
    if args.plot and not Path(args.plot).parent.is_dir():
        raise SpecError("--plot", f"folder {str(Path(args.plot).parent)!r} does not exist")
    spec = load_spec(args.spec)
    try:
        design = design_tube(spec)
    except DesignError as exc:
        if args.json:
            print(json.dumps({"spec": spec.name, "designed": False, "reason": str(exc)},
                             indent=2, sort_keys=True))
        raise
    if args.plot:
        from ..runtime.plots import plot_design
        atomic_write(Path(args.plot), lambda tmp: plot_design(spec, design, tmp))
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
    if design.input_proof is not None:          # [actuator]
        peaks = ", ".join(f"{p:.4g} <= {b:g}" for p, b in zip(design.input_proof.peak,
                                                              tube.input_bound))
        print(f"  PASS  input bound: law (13) asks at most [{peaks}] (proved)")
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


def configure_design(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen design``."""
    p.add_argument("spec", metavar="SPEC", help="bundled case name or spec file")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--plot", metavar="PNG", help="write a figure of the designed tube")
    p.set_defaults(handler=cmd_design)
