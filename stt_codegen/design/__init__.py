"""Tube design: reach segments, circumvents (5)-(9), via points, default gain, certificate.

Contract: :func:`.search.design_tube` turns a :class:`~stt_codegen.spec.Spec` into a
:class:`.result.Design` whose tube (:class:`~stt_codegen.tube.TubeDesign`) passes
:mod:`.certificate` (safety of the tube for every ``t >= 0``) and the sampling check, or
raises :class:`~stt_codegen.errors.DesignError` with the reason, its
:class:`.failures.FailureKind` and the best rejected tube. See ``docs/design.md``.
"""

__all__: list[str] = []
