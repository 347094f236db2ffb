"""Helpers of the issue-7 hostile-input tests (tests/test_hard_*.py): a small TOML writer."""

from __future__ import annotations

import json
import math
import tomllib
from importlib import resources


def toml_value(value) -> str:
    """One TOML value (inline tables and arrays; NaN and infinities as TOML spells them)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {toml_value(v)}"
                               for k, v in value.items()) + "}"
    raise TypeError(type(value))


def dumps(doc: dict) -> str:
    """A TOML document of top-level ``key = value`` lines."""
    return "".join(f"{json.dumps(str(k))} = {toml_value(v)}\n" for k, v in doc.items())


def bundled_doc(name: str) -> dict:
    data = resources.files("stt_codegen.cases").joinpath(name + ".toml").read_bytes()
    return tomllib.loads(data.decode())


def shape_docs() -> list[dict]:
    """The bundled specs, plus variants with a ball and a polytope obstacle (with tolerance)."""
    docs = [bundled_doc(f"omnirobot-s{k}") for k in (1, 2, 3)]
    ball = bundled_doc("omnirobot-s1")
    ball["obstacles"].append({"center": [3.5, 3.8], "radius": 0.3, "tolerance": 0.1})
    poly = bundled_doc("omnirobot-s2")
    poly["obstacles"].append({"vertices": [[3.2, 3.8], [3.9, 3.8], [3.5, 4.3]],
                              "tolerance": 0.08})
    poly3 = bundled_doc("omnirobot-s3")
    poly3["obstacles"].append({"vertices": [[2.8, 3.8, -0.5], [3.4, 3.8, -0.5],
                                            [3.0, 4.2, -0.5], [3.0, 4.0, 0.5]],
                               "dims": [0, 1, 2], "tolerance": 0.2})
    return docs + [ball, poly, poly3]
