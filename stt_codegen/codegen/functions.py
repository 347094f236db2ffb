"""The CasADi Functions whose bodies are deployed: the pieces of the model, each emitted once.

The generated API (C: ``<prefix>_tube``, ``_control``, ``_alpha_step``, ``_step``; Python:
``tube``, ``control``, ``alpha_step``, ``step``) is control flow over the spec's ``const``
tables (:mod:`stt_codegen.codegen.tables`) around the bodies of the pieces of
:mod:`stt_codegen.tube.pieces`, whose numbers are inputs:

* reach tube: find the active segment, ``progress_<profile>``, ``interpolate``; where the
  next segment has started (a blended corner), its ``progress_<profile>`` and ``blend``;
* circumvents: find the open windows (binary search on the sorted starts, then back over
  the running maximum of the ends), ``bump`` for each open one, ``fnu_init``,
  ``fnu_add``, ``fnu_finish`` per bound (a closed window would add exactly 0);
* tube (10): ``candidates``, then per dimension ``smooth_max_test`` and, only where the
  correction can change the max, ``smooth_max`` (likewise ``smooth_min``); rates:
  ``conflict``, ``alpha_rate``, ``candidate_rates``, ``smooth_max_rate``/``smooth_min_rate``;
* law (13): ``law``;
* implicit step of (11): ``later``, reach tube and circumvents at ``t + dt``,
  ``conflict``, then per component ``newton_start``, ``newton_root_start`` only when
  needed and ``NEWTON_ITERATIONS`` x ``newton_iteration`` in a loop that stops at a fixed
  point.

This is the composition :func:`stt_codegen.tube.model.build_model` makes over every
segment and circumvent, so the generated code computes the model's Functions bit for bit
(double precision, ``-ffp-contract=off``).
"""

from __future__ import annotations

import casadi as ca

from ..tube import pieces as P
from ..tube.model import TubeModel
from ..tube.parameters import LOWER, UPPER
from .tube_data import DATA_PROFILES

__all__ = ["clamped_control", "deployed_functions"]


def deployed_functions(model: TubeModel, every: bool = False) -> list[ca.Function]:
    """The deployed SX Functions of a design, in generation order.

    Parameters
    ----------
    model : TubeModel
        The design's CasADi model.
    every : bool, optional
        Every profile of :data:`~.tube_data.DATA_PROFILES` and both kinds of bounds,
        whatever the design uses: for the tube as data (:mod:`.tube_data`), which runs any
        tube of the spec's dimension with those profiles.

    Returns
    -------
    list of casadi.Function
        The pieces the generated code calls (:func:`~stt_codegen.tube.pieces.deployed_pieces`
        for the design's dimension, profiles, circumvent counts and actuator bound).
    """
    design = model.design
    if every:
        return P.deployed_pieces(design.dimension, DATA_PROFILES,
                                 saturated=design.input_bound is not None, blended=True)
    profiles = tuple(sorted({segment.profile for segment in design.segments}))
    members = [len(design.circumvents_on(i, side)) for i in range(design.dimension)
               for side in (LOWER, UPPER)]
    return P.deployed_pieces(design.dimension, profiles, single_bounds=1 in members,
                             multi_bounds=any(m > 1 for m in members),
                             saturated=design.input_bound is not None,
                             blended=design.blends_corners)


def clamped_control(model: TubeModel) -> ca.Function:
    """``control(x, t, alpha) -> (u, inside[, within_bound])``: the ``u``, ``inside`` (and,
    for a design with an actuator bound, ``within_bound``) of the model's step.

    Parameters
    ----------
    model : TubeModel
        The design's CasADi model (its ``controller_step``).

    Returns
    -------
    casadi.Function
        Inputs ``x`` (n), ``t`` (s), ``alpha`` (2n); outputs ``u`` (n) of law (13) with the
        deployed clamps, ``inside`` and, with an actuator bound, ``within_bound``.
    """
    step = model["controller_step"]
    n = model.design.dimension
    x = ca.SX.sym("x", n)
    t = ca.SX.sym("t")
    alpha = ca.SX.sym("alpha", 2 * n)
    u, _, inside, *within = step(x, t, 1e-3, alpha)
    return ca.Function("control", [x, t, alpha], [u, inside, *within], ["x", "t", "alpha"],
                       ["u", "inside", *(["within_bound"] if within else [])])
