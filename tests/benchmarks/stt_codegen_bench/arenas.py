"""Seeded random arenas in the spirit of the paper's Table I (section V).

The paper compares planners on 500 arenas with "obstacles placed at random" and gives no
further protocol. This module fixes one, documented and seeded:

* the state space is the case study's 5 m x 5 m arena ``[0, 5] x [0, 5]``;
* four obstacles of the case study's size, 1 m x 1 m, whose lower-left corners are drawn
  uniformly in ``[0, 4] x [0, 4]`` (they may overlap each other and touch the walls);
* a 0.5 m x 0.5 m start set whose lower-left corner is drawn uniformly in
  ``[0, 4.5] x [0, 4.5]``; ``x(0)`` is its centre;
* the case study's target ``[4.5, 5] x [4.5, 5]``;
* an arena in which the start set or the target meets an obstacle (touching counts), or
  the start set meets the target (a trivial task), is drawn again.

The plant is the single integrator ``x_dot = u + w`` in 2-D (the omnidirectional robot of
eq. (14) with the heading held at 0 is the same system), with the bundled specs'
disturbance bound ``|w_i| <= 0.1`` m/s and tube parameters (``delta_b = 0.2``,
``circumvent_sharpness = 0.1``, ``theta0 = 0.01``, ``kappa = 5``, ``mu = 1``, half-widths
``d_0 = d_T = 0.2``, 1 kHz), and ``t_c = 9`` s.

Arena ``k`` of seed ``S`` is drawn from ``numpy.random.default_rng([S, k])``, so it does
not depend on how many arenas are drawn or in which order or process.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stt_codegen.errors import SpecError
from stt_codegen.spec.loader import Box, Spec, parse_spec

__all__ = ["ARENA", "OBSTACLE_SIZE", "START_SIZE", "TARGET", "generate_arena", "generate_arenas"]

#: The case study's arena, target, obstacle size and start-set size, metres.
ARENA = Box((0.0, 0.0), (5.0, 5.0))
TARGET = Box((4.5, 4.5), (5.0, 5.0))
OBSTACLE_SIZE = 1.0
START_SIZE = 0.5
OBSTACLE_COUNT = 4
PRESCRIBED_TIME = 9.0
#: Draws allowed for one arena before giving up (never reached in practice: about one
#: draw in three is accepted).
MAX_DRAWS = 10_000

_TEMPLATE = """\
# Random arena {index} of seed {seed} (stt_codegen_bench.arenas): the paper's 5 m x 5 m
# arena, four 1 m x 1 m obstacles at random, a random 0.5 m x 0.5 m start set, the case
# study's target; single integrator x_dot = u + w, |w_i| <= 0.1.
name = "{name}"
prescribed_time = {t_c!r}

[state_space]
lower = [0.0, 0.0]
upper = [5.0, 5.0]

[initial]
lower = [{s0!r}, {s1!r}]
upper = [{s2!r}, {s3!r}]
half_width = [0.2, 0.2]

[target]
lower = [4.5, 4.5]
upper = [5.0, 5.0]
half_width = [0.2, 0.2]
{obstacles}
[tube]
delta_b = 0.2
circumvent_sharpness = 0.1
theta0 = 0.01
kappa = 5.0
mu = 1.0

[controller]
rate_hz = 1000.0

[plant]
model = "single-integrator"
disturbance_amplitude = 0.1
"""


@dataclass(frozen=True)
class Arena:
    """One random arena.

    Attributes
    ----------
    seed, index : int
        It is arena ``index`` of ``seed``.
    start : Box
        The start set ``X_0`` (0.5 m x 0.5 m), metres.
    obstacles : tuple of Box
        Four 1 m x 1 m boxes, metres.
    """

    seed: int
    index: int
    start: Box
    obstacles: tuple[Box, ...]

    @property
    def name(self) -> str:
        """Spec name, ``arena-S-K``."""
        return f"arena-{self.seed}-{self.index}"

    def to_toml(self) -> str:
        """The arena as a spec file, loadable by :func:`stt_codegen.spec.loader.load_spec`."""
        obstacles = "".join(
            f"\n[[obstacles]]\nlower = [{o.lower[0]!r}, {o.lower[1]!r}]\n"
            f"upper = [{o.upper[0]!r}, {o.upper[1]!r}]\n" for o in self.obstacles)
        s = self.start
        return _TEMPLATE.format(index=self.index, seed=self.seed, name=self.name,
                                t_c=PRESCRIBED_TIME, s0=s.lower[0], s1=s.lower[1],
                                s2=s.upper[0], s3=s.upper[1], obstacles=obstacles)

    def to_spec(self) -> Spec:
        """The arena's validated :class:`~stt_codegen.spec.loader.Spec` (parsed from :meth:`to_toml`)."""
        return parse_spec(self.to_toml())


def _square(corner: np.ndarray, size: float) -> Box:
    return Box(tuple(float(v) for v in corner), tuple(float(v + size) for v in corner))


def generate_arena(seed: int, index: int) -> Arena:
    """Draw arena ``index`` of ``seed`` (see the module docstring for the protocol).

    Parameters
    ----------
    seed : int
        Non-negative.
    index : int
        Non-negative.

    Returns
    -------
    Arena
        The arena: its start box and obstacles (``to_spec()`` and ``to_toml()`` add the
        fixed target).

    Raises
    ------
    SpecError
        Negative ``seed`` or ``index`` (fields ``seed``, ``index``).
    """
    if seed < 0:
        raise SpecError("seed", f"must be non-negative, got {seed}")
    if index < 0:
        raise SpecError("index", f"must be non-negative, got {index}")
    rng = np.random.default_rng([seed, index])
    room_o = ARENA.upper[0] - OBSTACLE_SIZE
    room_s = ARENA.upper[0] - START_SIZE
    for _ in range(MAX_DRAWS):
        obstacles = tuple(_square(rng.uniform(0.0, room_o, 2), OBSTACLE_SIZE)
                          for _ in range(OBSTACLE_COUNT))
        start = _square(rng.uniform(0.0, room_s, 2), START_SIZE)
        if start.meets(TARGET) or any(o.meets(start) or o.meets(TARGET) for o in obstacles):
            continue
        return Arena(seed, index, start, obstacles)
    raise AssertionError("unreachable: no acceptable arena in MAX_DRAWS draws")  # pragma: no cover


def generate_arenas(count: int, seed: int) -> list[Arena]:
    """Arenas ``0 .. count - 1`` of ``seed``.

    Parameters
    ----------
    count : int
        Number of arenas, >= 1.
    seed : int
        Arena seed, >= 0.

    Returns
    -------
    list of Arena
        Arena ``k`` is :func:`generate_arena` ``(seed, k)``.

    Raises
    ------
    SpecError
        ``count < 1`` (field ``count``) or a negative seed.
    """
    if count < 1:
        raise SpecError("count", f"must be at least 1, got {count}")
    return [generate_arena(seed, k) for k in range(count)]
