"""``sampled.input_bound``: the deployed law (13) never asks an input for more than
``[actuator] input_bound``.

From the sampled-data check (:mod:`.sampled`), which proves a bound ``E_k,i`` of
``|e_i(t_k)|`` at every sample for every plant of ``[assumptions]``, and the certified
enclosure of the tube on each sampling interval (a lower bound ``W_k,i`` of its width
there), :func:`~stt_codegen.design.input_bound.input_peak` bounds every input the
controller computes: ``|u_k,i| <= 4 k phi(E_k,i) / max(W_k,i, GAMMA_D_MIN)``. The argument
is in ``docs/sampled-data.md`` ("The input bound"). The design asks this prover
(:func:`prove_input_bound`) before it accepts a tube, and ``verify`` reports it
(:func:`stt_codegen.verification.sampled.input_bound_check`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from .enclosures import enclose_tube
from ..input_bound import InputProof, input_peak
from ..samples import TubeSamples
from ...spec.loader import Spec
from ...tube import reference
from ...tube.parameters import GAMMA_D_MIN, TubeDesign
from .sampled import SampledCheck, sampled_check_of
from .sampled_axis import phi_scalar

__all__ = ["LIMIT_SLACK", "certified_widths", "prove_input_bound", "sampled_error_bound",
           "width_bounds"]

#: The relative shade below a sample's bound of ``|u|`` that ``prove_input_bound``'s
#: ``limit`` is asked (far above an ulp, far below any margin a verdict turns on).
LIMIT_SLACK = 1e-9


def sampled_error_bound(result: SampledCheck, samples: TubeSamples) -> np.ndarray | None:
    """The sampled check's bound of ``|e_i(t_k)|``, shape (K, n), or ``None`` if it failed.

    The one place that reads the sampled check's result for the input bound: its
    per-sample bound (``abs_e``) when it gives one, else its overall bound (``max_abs_e``,
    the largest ``|e|`` at any sample) at every sample.

    Parameters
    ----------
    result : SampledCheck
        The sampled closed-loop check of the design (:func:`~.sampled.check_sampled`).
    samples : TubeSamples
        The tube at the sampling instants ``t_k`` (K of them).

    Returns
    -------
    ndarray, shape (K, n), or None
        The bound of ``|e_i(t_k)|`` per sample and axis (each in ``[0, 1)``); ``None`` when
        the check failed.
    """
    if not result.passed:
        return None
    n = samples.gamma_lower.shape[1]
    per_sample = getattr(result, "abs_e", None)
    if per_sample is not None and np.shape(per_sample) == (samples.t.size, n):
        return np.asarray(per_sample, dtype=float)
    level = float(result.data.get("max_abs_e", result.level))
    return np.full((samples.t.size, n), level)


def width_bounds(tube: TubeDesign, samples: TubeSamples) -> tuple[np.ndarray, np.ndarray]:
    """A lower and an upper bound of the tube's width at every sample, shape (K, n) each:
    the certified enclosure of the interval that starts there (the last sample ends the
    last one)."""
    enclosure = enclose_tube(tube, samples)
    narrow = enclosure.upper_min - enclosure.lower_max
    wide = enclosure.upper_max - enclosure.lower_min
    return np.vstack([narrow, narrow[-1:]]), np.vstack([wide, wide[-1:]])


def certified_widths(tube: TubeDesign, samples: TubeSamples) -> np.ndarray:
    """A lower bound of the tube's width at every sample, shape (K, n) (:func:`width_bounds`'
    first)."""
    return width_bounds(tube, samples)[0]


def prove_input_bound(tube: TubeDesign, spec: Spec, *, per_axis_first: bool = False,
                      limit: Callable[[list[float]], bool] | None = None,
                      initial_error: tuple[tuple[float, float], ...] | None = None
                      ) -> InputProof:
    """The proved peak of each input of law (13) along ``tube`` for the spec's plants.

    Parameters
    ----------
    tube : TubeDesign
        With its gain (the input bound's clamp, if any, plays no part: the proof shows
        it never acts).
    spec : Spec
        Its plant class (:func:`~stt_codegen.design.certificate.plant_class.plant_class`: the model's
        bounds evaluated on the tube per interval, and ``[assumptions]``), the one
        ``sampled.tube_kept`` judges.
    per_axis_first : bool
        Bound ``e`` by the per-axis argument where it passes (``verify``'s check, cheaper;
        bounds no tighter than the Lyapunov balls') instead of the whole check with the
        balls everywhere (the default; the peaks of ``[actuator]`` are proved from it).
    limit : callable, optional
        ``(bound of |u_i(t_k)|, a list of n floats) -> bool``, true where the bound at a sample
        already breaks what the caller accepts (a verdict that needs no whole peak;
        monotone: a larger bound breaks it too), asked a relative :data:`LIMIT_SLACK`
        below the bound: the check stops at the first such sample, and the proof is
        partial (:attr:`~stt_codegen.design.input_bound.InputProof.complete` false: its
        peaks are those up to that sample). The check runs whole where no sample breaks
        it, so a proof that meets the caller's bound is whole; where the whole check is
        already kept (:func:`~.sampled.cached_check`), the whole proof from it
        (:func:`~.sampled.sampled_check_of`'s ``stop_for``); a proof that meets the
        caller's bound is the same with or without ``limit``. With ``per_axis_first``,
        the per-axis argument stops there (the balls run only where it fails the check
        itself). Ignored with ``[controller] compensate_delay``.
    initial_error : tuple of (float, float), optional
        The sampled check from this box of ``e(0)`` (:func:`~.sampled.check_sampled`).

    Returns
    -------
    InputProof
        Not proved when the sampled-data check fails (its reason); the horizon is the
        sampled check's, ``1.1 t_c``.

    Raises
    ------
    SpecError
        More samples than the step budget (as :func:`~stt_codegen.design.samples.sample_tube`).
    """
    kept: list[tuple[np.ndarray, np.ndarray]] = []      # (widths, |u| per phi), once

    def widths(samples: TubeSamples) -> tuple[np.ndarray, np.ndarray]:
        """The certified widths at the samples and law (13)'s ``|u|`` per ``phi(|e|)``."""
        if not kept:
            with reference.numpy_math():
                width = certified_widths(tube, samples)
            kept.append((width, 4.0 * tube.gain / np.maximum(width, GAMMA_D_MIN)))
        return kept[0]

    def breaks(per_phi: list[float], abs_e: list[float]) -> bool:
        # a shade below the bound input_peak computes from the same numbers (libm's atanh
        # here, numpy's there, may differ by an ulp): a sample breaks the limit only where
        # the whole proof's bound does
        return bool(limit([p * phi_scalar(s) * (1.0 - LIMIT_SLACK)
                           for p, s in zip(per_phi, abs_e)]))

    def stop_for(samples: TubeSamples):
        per_phi = widths(samples)[1].tolist()
        return lambda k, abs_e: breaks(per_phi[k], abs_e)

    # the check is computed once per (tube, spec, per_axis_first) in a process:
    # sampled_check_of samples with the oracle's exp/log/tanh as numpy's ufuncs
    samples, result = sampled_check_of(tube, spec, per_axis_first,
                                       None if limit is None else stop_for, initial_error)
    horizon = float(samples.t[-1])
    width = widths(samples)[0]
    if "stopped_at" in result.data:
        k = len(result.abs_e)
        return replace(input_peak(tube.gain, result.abs_e, width[:k], samples.t[:k],
                                  horizon),
                       complete=False, reason=f"the bound of the input passes the limit at "
                                              f"t = {result.data['stopped_at']:.4f} s (the "
                                              f"check stopped there)")
    abs_e = sampled_error_bound(result, samples)
    if abs_e is None:
        n = tube.dimension
        return InputProof(False, (np.inf,) * n, (0.0,) * n, horizon,
                          f"the sampled-data check fails: {result.reason}")
    return input_peak(tube.gain, abs_e, width, samples.t, horizon)
