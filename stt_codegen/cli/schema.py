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
        The parsed arguments (none are read).

    Returns
    -------
    int
        0.
    """
    from ..spec.schema import json_schema
    print(json.dumps(json_schema(), indent=2, sort_keys=True))
    return 0


def configure_schema(p: argparse.ArgumentParser) -> None:
    """Arguments of ``stt-codegen schema`` (none).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser; its ``handler`` is set to :func:`cmd_schema`.
    """
    p.set_defaults(handler=cmd_schema)
