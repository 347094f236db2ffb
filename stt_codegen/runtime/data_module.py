"""Backend ``python`` for tubes that change at run time: one generated module, tubes as data.

:class:`TubeDataModule` generates the Python module of a spec with ``--tube-data``
(:mod:`stt_codegen.codegen.tube_data`) once and executes it from memory;
:meth:`~TubeDataModule.load` packs any tube of the spec's dimension into the module's
``TubeData`` (the tables' order, :func:`~stt_codegen.codegen.tables.design_table_rows`, as
:func:`~.data_controller.pack_tube` packs the C's struct) and returns a controller that
runs it. :func:`~stt_codegen.runtime.sensed.simulate_sensed` runs its switched tubes this
way on backend ``python`` (before, it generated a module per tube).
"""

from __future__ import annotations

import math

import numpy as np

from ..codegen.generate import generate_files
from ..codegen.look_ahead_source import look_ahead_python_file
from ..codegen.options import Options
from ..codegen.tables import design_table_rows
from ..codegen.tube_data import TubeCapacity, fitting_capacity, require_capacity
from ..errors import SpecError
from ..tube.look_ahead import LookAhead
from ..tube.parameters import TubeDesign
from .compiled import DesignSpec, load_python_module

__all__ = ["TubeDataModule", "first_order_data_module", "look_ahead_data_module",
           "no_data_module"]


class TubeDataModule:
    """The generated Python module of a spec with the tube as data, generated once.

    The Python counterpart of :class:`~.data_controller.TubeDataController`, with the same
    methods; the module computes what the C computes, bit for bit in double precision.

    Parameters
    ----------
    design : TubeDesign
        The spec's tube: its dimension, actuator bound and state space fix the generated
        module; its own tube is ``DESIGN_TUBE``.
    capacity : TubeCapacity, optional
        The most segments and windows of one tube; default 8 segments and 32 windows, or
        more when the design has more.
    look_ahead : LookAhead, optional
        A differential-drive base's axle offset and limits: the look-ahead variant's module
        (:func:`~stt_codegen.codegen.look_ahead_source.look_ahead_python_file`), whose step
        takes the base's state ``(x, y, theta)`` and returns ``(v, omega)``, and whose
        switch tests the look-ahead point; default law (13)'s module.

    Examples
    --------
    >>> import stt_codegen as stt
    >>> from stt_codegen.runtime.data_module import TubeDataModule
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> library = TubeDataModule(design.tube)
    >>> library.check(library.pack(design.tube))                 # the module's TUBE_OK
    0
    """

    name = "python"

    def __init__(self, design: TubeDesign, capacity: TubeCapacity | None = None,
                 look_ahead: LookAhead | None = None) -> None:
        capacity = capacity or fitting_capacity(design)
        spec = DesignSpec(design)
        name = f"{spec.c_name}.py"
        if look_ahead is None:
            text = generate_files(spec, design, Options(("python",), "double", capacity))[name]
        else:
            text = look_ahead_python_file(design, look_ahead, spec.c_name,
                                          capacity=capacity)[name].encode()
        self.module = load_python_module(text, spec.c_name)
        self.n, self.capacity, self.design = design.dimension, capacity, design

    def pack(self, design: TubeDesign):
        """``design`` as the module's ``TubeData``.

        Raises
        ------
        SpecError
            The tube does not fit the capacity (field ``tube_data``).
        """
        require_capacity(design, self.capacity)
        m = self.module
        tables = design_table_rows(design, float, False)
        return m.TubeData(
            m.Parameters(*(value for _, value, _ in tables.parameters)), tables.bounds,
            tables.members, tables.multi,
            [(r["start"], r["end"], r["profile"], r["from"], r["to"]) for r in tables.segments],
            [tuple(r[k] for k in ("start", "end", "center", "radius", "sharpness", "height",
                                  "max_end", "bound")) for r in tables.windows])

    def check(self, tube) -> int:
        """The module's ``tube_check`` of a packed tube (``0``: well formed)."""
        return int(self.module.tube_check(tube))

    def load(self, design: TubeDesign) -> "_Loaded":
        """A controller running ``design``'s tube (packed, checked) on this module.

        Raises
        ------
        SpecError
            The tube does not fit the capacity, or ``tube_check`` refuses it (field
            ``tube_data``).
        """
        tube = self.pack(design)
        code = self.check(tube)
        if code != 0:
            raise SpecError("tube_data", f"the generated module's tube check refused the "
                                         f"tube (code {code}, docs/sensing.md)")
        return _Loaded(self.module, tube)


class _Loaded:
    """``step(x, t, dt, alpha) -> (u, alpha_next, status)`` of one packed tube."""

    name = "python"

    def __init__(self, module, tube) -> None:
        self.module, self.tube = module, tube

    def step(self, x, t, dt, alpha):
        u, alpha_next, status = self.module.step(
            self.tube, [float(v) for v in np.ravel(x)], float(t), float(dt),
            [float(v) for v in np.ravel(alpha)])
        return np.array(u), np.array(alpha_next), int(status)

    def switch_error(self, x) -> float:
        """``max_i |e_i|`` of the state ``x`` in this tube at its ``t = 0`` (``alpha = 0``),
        as the generated ``switch`` computes it; ``inf`` where it refuses for another
        reason (a state that is not finite)."""
        m = self.module
        scratch = m.Active()
        code = m.switch(scratch, self.tube, 0.0, [float(v) for v in np.ravel(x)], 0.0)
        return float(scratch.error) if code in (m.SWITCH_DONE, m.SWITCH_OUTSIDE) else math.inf


def first_order_data_module(design) -> TubeDataModule:
    """Law (13)'s Python module with the tube as data for a first-order ``design`` (the
    variant's role ``data_module``)."""
    return TubeDataModule(design.tube)


def look_ahead_data_module(design) -> TubeDataModule:
    """The look-ahead variant's Python module with the tube as data for a
    differential-drive ``design`` (its axle offset and limits; the variant's role
    ``data_module``)."""
    return TubeDataModule(design.tube, look_ahead=design.look_ahead)


def no_data_module(design) -> TubeDataModule:
    """The role ``data_module`` of a variant whose Python takes no tube as data.

    Raises
    ------
    SpecError
        Always (field ``tube_data``, :func:`~stt_codegen.codegen.tube_data.require_tube_data`).
    """
    from ..codegen.tube_data import require_tube_data
    require_tube_data(design.spec, ("python",))
    raise AssertionError("require_tube_data refuses every variant without a Python tube as "
                         "data")
