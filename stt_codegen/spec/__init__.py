"""Specs: the task (Definition 2.1) and its design parameters, read from TOML and validated.

Contract: :func:`load_spec` / :func:`parse_spec` return a frozen :class:`Spec` or raise
:class:`~stt_codegen.errors.SpecError` naming the field and the reason. Balls and convex
polytopes are covered by boxes here (:mod:`.covering`, Remark 3.1), so every later stage
sees boxes only (``Spec.obstacle_boxes()``) and the shapes as given (``Spec.unsafe_sets``).
One validation path: :mod:`.schema` checks every value, :mod:`.loader` only the rules that
relate fields to each other; plant-model facts are :mod:`.plants` (docs/architecture.md,
"One validation path").
"""

from .loader import Box, Obstacle, Spec, UnsafeSet, bundled_cases, load_spec, parse_spec

__all__ = ["Box", "Obstacle", "Spec", "UnsafeSet", "bundled_cases", "load_spec", "parse_spec"]
