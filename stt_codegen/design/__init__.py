"""Tube design: windows (5), circumvent choices (6)-(9), default gain, and the certificate.

Contract: :func:`.search.design_tube` turns a :class:`~stt_codegen.spec.Spec` into a
:class:`~stt_codegen.tube.TubeDesign` that passes :mod:`.certificate` (safety of the
tube for every ``t``) and the sampling checks, or raises
:class:`~stt_codegen.errors.DesignError` with the reason.
"""
