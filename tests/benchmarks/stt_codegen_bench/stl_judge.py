"""Judge a trajectory on an stlpy formula with rtamt, at the samples and on a fine grid.

stlpy builds its temporal operators by unrolling them over integer steps:
``phi.always(a, b)`` is an ``STLTree`` of ``b - a + 1`` copies of ``phi`` joined by ``and``
at the timesteps ``a..b``, ``eventually`` the same with ``or``, and ``phi.until(psi, a, b)``
an ``or`` over ``t'`` of ``phi`` at ``a..t'-1`` and ``psi`` at ``t'``. :func:`formula_text`
reads those shapes back as rtamt's ``always[a dt, b dt]``, ``eventually[...]`` and
``until[...]`` (seconds; at the top, an ``until`` over the whole signal as rtamt's
unbounded one, the same at ``t = 0``), and a tree whose timesteps are all 0 as a plain ``and``/``or``;
any other shape is refused (``ValueError``), never guessed.

Each predicate (stlpy's ``LinearPredicate`` ``a y - b >= 0`` or ``NonlinearPredicate``
``g(y) >= 0``) becomes one rtamt variable ``p<k> >= 0`` whose values are the predicate's own
robustness, computed by stlpy's predicate on the signal: the boxes and circles are stlpy's
own, unclipped. rtamt's discrete-time monitor then evaluates the formula on a signal
sampled every ``period`` seconds: every step (the samples) or every 0.01 s (the fine grid).
At the samples, the robustness equals stlpy's own ``formula.robustness(y, 0)``
(``tests/test_bench_stl.py`` checks it); on the fine grid ``always`` ranges over every
grid point, so a run that leaves a box between samples is caught.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["FINE_PERIOD", "formula_text", "robustness", "stlpy_robustness"]

#: The fine grid's spacing, seconds (100 Hz).
FINE_PERIOD = 0.01


def _interval(a: int, b: int, dt: float) -> str:
    return f"[{a * dt:.12g},{b * dt:.12g}]"


def _is_until(tree: Any) -> tuple[Any, Any, int, int] | None:
    """``(phi, psi, a, b)`` when ``tree`` is stlpy's unrolled ``phi U[a,b] psi``."""
    from stlpy.STL import STLTree
    children = tree.subformula_list
    if tree.combination_type != "or" or any(t != 0 for t in tree.timesteps):
        return None
    if not all(isinstance(c, STLTree) and c.combination_type == "and" for c in children):
        return None
    first = children[0]
    a = first.timesteps[0]
    psi = first.subformula_list[-1]
    phi = children[-1].subformula_list[0] if len(children) > 1 else None
    for k, child in enumerate(children):
        if child.timesteps != list(range(a, a + k + 1)):
            return None
        if child.subformula_list[-1] is not psi:
            return None
        if any(s is not phi for s in child.subformula_list[:-1]):
            return None
    if phi is None:
        return None
    return phi, psi, a, a + len(children) - 1


def formula_text(formula: Any, dt: float, horizon: float | None = None,
                 ) -> tuple[str, list[Any]]:
    """rtamt's text of an stlpy formula, and its predicates (module notes).

    Parameters
    ----------
    formula : stlpy.STL.STLFormula
        The scenario's formula (``GetSpecification()``, not simplified).
    dt : float
        One step, seconds.
    horizon : float, optional
        The end of the signal the text will be evaluated on, s. An ``until[0, b]`` that is
        not under a temporal operator (so evaluated at ``t = 0`` only) and whose ``b``
        reaches the horizon is written as rtamt's unbounded ``until``: on that signal the
        two are the same at ``t = 0``, and rtamt evaluates the unbounded one in linear
        time (its bounded one takes minutes on the 100 Hz grid).

    Returns
    -------
    text : str
        The formula in rtamt's syntax over variables ``p0, p1, ...``.
    predicates : list
        The stlpy predicate of variable ``p<k>`` at index ``k``.

    Raises
    ------
    ValueError
        A tree shape that is none of always, eventually, until or a plain and/or.
    """
    from stlpy.STL import STLTree
    predicates: list[Any] = []
    index: dict[int, int] = {}

    def walk(node: Any, top: bool = False) -> str:
        if not isinstance(node, STLTree):
            if id(node) not in index:
                index[id(node)] = len(predicates)
                predicates.append(node)
            return f"(p{index[id(node)]} >= 0)"
        children, steps = node.subformula_list, node.timesteps
        until = _is_until(node)
        if until is not None:
            phi, psi, a, b = until
            whole = top and a == 0 and horizon is not None and b * dt >= horizon - 1e-9
            window = "" if whole else _interval(a, b, dt)
            return f"({walk(phi)} until{window} {walk(psi)})"
        if len(children) > 1 and all(c is children[0] for c in children) \
                and steps == list(range(steps[0], steps[0] + len(steps))):
            op = "always" if node.combination_type == "and" else "eventually"
            return f"({op}{_interval(steps[0], steps[-1], dt)} {walk(children[0])})"
        if all(t == 0 for t in steps):
            join = f" {node.combination_type} "
            return "(" + join.join(walk(c, top) for c in children) + ")"
        raise ValueError(f"formula shape not recognised: {node.combination_type} at "
                         f"timesteps {steps}")

    return walk(formula, True), predicates


def _predicate_values(predicate: Any, y: np.ndarray) -> np.ndarray:
    """The predicate's robustness at every row of ``y`` (shape (N, d)): ``a y - b`` over the
    entries a linear predicate weighs, ``g(y)`` for a nonlinear one."""
    if hasattr(predicate, "a"):
        a = np.ravel(predicate.a)
        used = np.flatnonzero(a)
        values = y[:, used] @ a[used] - float(np.ravel(predicate.b)[0])
    else:
        values = np.array([float(np.ravel(predicate.g(row))[0]) for row in y])
    if not np.all(np.isfinite(values)):
        raise ValueError("a predicate reads a signal entry the run does not give "
                         "(only the positions are filled)")
    return values


def robustness(formula: Any, dt: float, times: np.ndarray, y: np.ndarray,
               period: float) -> float:
    """rtamt's robustness at ``t = 0`` of an stlpy formula on a sampled signal.

    Parameters
    ----------
    formula : stlpy.STL.STLFormula
        The scenario's formula.
    dt : float
        One stlpy step, seconds (the formula's time unit).
    times : ndarray, shape (N,)
        Sampling instants ``k * period``, s, from 0 to at least the formula's horizon.
    y : ndarray, shape (N, d)
        stlpy's output signal at ``times`` (``d`` its output dimension; the entries the
        run does not give are NaN, and a predicate that reads one is refused).
    period : float
        Spacing of ``times``, s.

    Returns
    -------
    float
        The robustness (positive: satisfied with that margin, state units).

    Raises
    ------
    ValueError
        A formula shape :func:`formula_text` refuses, or a predicate reading a NaN entry.
    """
    import rtamt
    text, predicates = formula_text(formula, dt, float(times[-1]))
    spec = rtamt.StlDiscreteTimeSpecification()
    data: dict[str, list[float]] = {"time": [float(t) for t in times]}
    for k, predicate in enumerate(predicates):
        spec.declare_var(f"p{k}", "float")
        data[f"p{k}"] = _predicate_values(predicate, y).tolist()
    spec.spec = text
    spec.set_sampling_period(round(period * 1e6), "us", 0.01)
    spec.parse()
    return float(spec.evaluate(data)[0][1])


def stlpy_robustness(formula: Any, y: np.ndarray) -> float:
    """stlpy's own robustness at step 0 of a signal sampled once per step.

    Parameters
    ----------
    formula : stlpy.STL.STLFormula
    y : ndarray, shape (T + 1, d)

    Returns
    -------
    float
    """
    return float(np.ravel(formula.robustness(y.T, 0))[0])
