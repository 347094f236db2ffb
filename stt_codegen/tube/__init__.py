"""The tube and its controller as mathematics: parameters, the CasADi model, the numpy oracle.

Contract: :class:`TubeDesign` holds every number of one tube (:mod:`.parameters`).
:mod:`.model` turns it into CasADi ``Function``s, the single source of every deployed
formula; :mod:`.reference` is the deliberate, independent second implementation in numpy
(written from the paper, hand-derived derivatives, bisection), the oracle for the tests.
"""

from .parameters import Circumvent, TubeDesign

__all__ = ["Circumvent", "TubeDesign"]
