"""``stt-codegen schema``: print the JSON Schema of spec files (draft 7)."""

from __future__ import annotations

import argparse
import json

__all__ = ["cmd_schema", "configure_schema"]


def cmd_schema(args: argparse.Namespace) -> int:
    """Print the schema of :mod:`stt_codegen.spec.schema`; exit 0.

    Parameters
    ----------
    args : argparse.Namespace
        ``fleet``: the schema of fleet files instead (docs/fleets.md).

    Returns
    -------
    int
        0.
    """
    if args.fleet:
        from ..spec.fleet import fleet_json_schema
        print(json.dumps(fleet_json_schema(), indent=2, sort_keys=True))
        return 0
    from ..spec.schema import json_schema
    print(json.dumps(json_schema(), indent=2, sort_keys=True))
    return 0


def configure_schema(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen schema``: ``--fleet``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; gets ``--fleet``, and its ``handler`` is set to
        :func:`cmd_schema`.
    """
    p.add_argument("--fleet", action="store_true",
                   help="the schema of fleet files (several robots) instead")
    p.set_defaults(handler=cmd_schema)
