"""Seeded random arenas for the design acceptance test, and a corridor check.

Arena ``k`` of seed ``s``: the 5 m x 5 m state space, 5-8 box obstacles with sides drawn in
[0.4, 1.4] m, a 0.5 m x 0.5 m start set and target set anywhere (not meeting an obstacle or
each other), no ``[tube]`` or ``[controller]`` section (the toolkit's defaults).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from stt_codegen.spec.loader import Spec, parse_spec

SIZE = 5.0
#: The disc that must fit through: its radius, metres.
DISC_RADIUS = 0.15
#: Grid of the corridor check, metres.
GRID = 0.02


def _meets(a_lo, a_hi, b_lo, b_hi) -> bool:
    return bool(np.all(a_lo <= b_hi) and np.all(b_lo <= a_hi))


def arena_toml(seed: int, index: int) -> str:
    rng = np.random.default_rng([seed, index, 10])
    while True:
        count = int(rng.integers(5, 9))
        obstacles = []
        for _ in range(count):
            side = rng.uniform(0.4, 1.4, 2)
            lo = rng.uniform(0.0, SIZE - side)
            obstacles.append(([float(v) for v in lo], [float(v) for v in lo + side]))
        start_lo = [float(v) for v in rng.uniform(0.0, SIZE - 0.5, 2)]
        goal_lo = [float(v) for v in rng.uniform(0.0, SIZE - 0.5, 2)]
        boxes = [(np.array(start_lo), np.array(start_lo) + 0.5),
                 (np.array(goal_lo), np.array(goal_lo) + 0.5)]
        if _meets(*boxes[0], *boxes[1]):
            continue
        if any(_meets(*b, np.array(o[0]), np.array(o[1])) for b in boxes for o in obstacles):
            continue
        break
    lines = [f'name = "random-{seed}-{index}"', "prescribed_time = 9.0",
             "[state_space]", "lower = [0.0, 0.0]", f"upper = [{SIZE}, {SIZE}]",
             "[initial]", f"lower = [{start_lo[0]!r}, {start_lo[1]!r}]",
             f"upper = [{start_lo[0] + 0.5!r}, {start_lo[1] + 0.5!r}]",
             "[target]", f"lower = [{goal_lo[0]!r}, {goal_lo[1]!r}]",
             f"upper = [{goal_lo[0] + 0.5!r}, {goal_lo[1] + 0.5!r}]"]
    for lo, hi in obstacles:
        lines += ["[[obstacles]]", f"lower = [{lo[0]!r}, {lo[1]!r}]",
                  f"upper = [{hi[0]!r}, {hi[1]!r}]"]
    return "\n".join(lines) + "\n"


def arena_spec(seed: int, index: int) -> Spec:
    return parse_spec(arena_toml(seed, index))


def disc_can_pass(spec: Spec) -> bool:
    """A disc of radius DISC_RADIUS can move from x(0) to the target centre (grid search
    over the free centres, obstacles and walls inflated by the radius)."""
    cells = int(round(SIZE / GRID)) + 1
    xs = np.linspace(0.0, SIZE, cells)
    x, y = np.meshgrid(xs, xs, indexing="ij")
    free = ((x >= DISC_RADIUS) & (x <= SIZE - DISC_RADIUS)
            & (y >= DISC_RADIUS) & (y <= SIZE - DISC_RADIUS))
    for box in spec.obstacle_boxes():
        dx = np.maximum(np.maximum(box.lower[0] - x, x - box.upper[0]), 0.0)
        dy = np.maximum(np.maximum(box.lower[1] - y, y - box.upper[1]), 0.0)
        free &= dx * dx + dy * dy > DISC_RADIUS ** 2

    def cell(p):
        return tuple(int(round(v / GRID)) for v in p)

    start, goal = cell(spec.initial_state), cell(spec.target_center)
    if not (free[start] and free[goal]):
        return False
    seen = np.zeros_like(free)
    seen[start] = True
    queue = deque([start])
    while queue:
        i, j = queue.popleft()
        if (i, j) == goal:
            return True
        for a, b in ((i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)):
            if 0 <= a < cells and 0 <= b < cells and free[a, b] and not seen[a, b]:
                seen[a, b] = True
                queue.append((a, b))
    return False
