"""What several commands share: their common arguments and the design step.

Heavy packages are imported inside the functions, so that configuring a command (``--help``)
imports nothing but the standard library.
"""

from __future__ import annotations

import argparse
import json
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..design.result import Design


def add_spec_argument(p: argparse.ArgumentParser) -> None:
    """The positional ``SPEC``: a bundled case name or a spec file."""
    p.add_argument("spec", metavar="SPEC", help="bundled case name or spec file")


def add_json_argument(p: argparse.ArgumentParser, text: str = "print one JSON object") -> None:
    """``--json``: print one JSON document on standard output instead of text."""
    p.add_argument("--json", action="store_true", help=text)


def default_backend() -> str:
    """The backend ``simulate`` and ``demo`` use unless told otherwise."""
    return "c"


def add_backend_argument(p: argparse.ArgumentParser) -> None:
    """``--backend``: the controller implementation (``stt_codegen.runtime.backends``)."""
    from ..runtime.backends import backend_names
    p.add_argument("--backend", default=default_backend(), choices=backend_names(),
                   help="controller implementation (default: %(default)s)")


def print_json(data: Any) -> None:
    """Print ``data`` as one indented JSON document with sorted keys."""
    print(json.dumps(data, indent=2, sort_keys=True))


def load_and_design(spec_arg: str) -> Design:
    """Load the spec ``SPEC`` names and design its tube.

    Raises
    ------
    SpecError
        The spec is invalid or cannot be found.
    DesignError
        No certified tube exists for it (exit code 1, the reason on standard error).
    """
    from ..design.search import design_tube
    from ..spec.loader import load_spec
    return design_tube(load_spec(spec_arg))
