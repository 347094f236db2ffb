"""The command ``stt-codegen verify``: every check of one design, with its evidence.

The entry point is :func:`stt_codegen.verification.command.verify` (the front door's
``stt_codegen.verify``): ``verify(design)`` or ``verify(spec)`` returns a
:class:`~stt_codegen.proofs.check.VerificationReport`. It runs the SymPy proofs of
:mod:`stt_codegen.proofs` and words the design's numeric certificates
(:mod:`stt_codegen.design.certificate`) as checks. The modules:

* :mod:`.command` -- every check of one design, :func:`~.command.verify`;
* :mod:`.sampled` -- the first order's sampled closed loop (``sampled.*``);
* :mod:`.cascade` -- the second order's sampled cascade (``cascade.sampled``,
  ``cascade.input_bound``, ``cascade.plant_within_assumptions``);
* :mod:`.plant_within` -- whether the spec's own plant lies in the certified class, for
  both orders;
* :mod:`.class_search` -- members of a plant class that leave the tube, replayed on the
  deployed controller (:mod:`stt_codegen.runtime.backends`).
"""

__all__ = []
