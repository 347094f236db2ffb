"""Backend ``c`` for tubes that change at run time: one compiled controller, tubes as data.

:class:`TubeDataController` generates the C of a spec with ``--tube-data``
(:mod:`stt_codegen.codegen.tube_data`), compiles it once into the build cache and loads it
with ``ctypes``; :meth:`~TubeDataController.load` packs any tube of the spec's dimension
into the ``<P>_tube_data`` struct (the tables' order, :func:`~stt_codegen.codegen.tables.design_table_rows`)
and returns a controller that runs it. :func:`~stt_codegen.runtime.sensed.simulate_sensed`
runs its switched tubes this way on backend ``c``.
"""

from __future__ import annotations

import ctypes
import math
from functools import lru_cache

import numpy as np

from ..codegen.generate import generate_files
from ..codegen.look_ahead_source import look_ahead_c_files
from ..codegen.options import Options
from ..codegen.tables import PARAMETERS, design_table_rows
from ..codegen.tube_data import TubeCapacity, fitting_capacity, require_capacity
from ..tube.look_ahead import LookAhead
from ..tube.parameters import TubeDesign
from .compiled import DesignSpec, build_shared

__all__ = ["TubeDataController", "active_struct", "first_order_data_controller",
           "look_ahead_data_controller", "no_data_controller", "pack_tube", "tube_struct"]


def tube_struct(n: int, capacity: TubeCapacity, real=ctypes.c_double) -> type:
    """The ``ctypes`` layout of ``<P>_tube_data`` (the generated header's), one class per
    layout (``ctypes`` takes a struct only as the class its function was declared with).

    Parameters
    ----------
    n : int
        State dimension.
    capacity : TubeCapacity
        The arrays' sizes.
    real : ctypes type, optional
        ``c_double`` (default) or ``c_float``.

    Returns
    -------
    type
        A ``ctypes.Structure`` subclass.
    """
    return _layout(int(n), capacity, real)


@lru_cache(maxsize=None)
def _layout(n: int, capacity: TubeCapacity, real) -> type:
    m = 2 * n

    class Parameters(ctypes.Structure):
        _fields_ = [(field, real) for field, _, _ in PARAMETERS]

    class Segment(ctypes.Structure):
        _fields_ = [("start", real), ("end", real), ("profile", ctypes.c_int),
                    ("from_", real * m), ("to", real * m)]

    class Window(ctypes.Structure):
        _fields_ = [(name, real) for name in ("start", "end", "center", "radius", "sharpness",
                                              "height", "max_end")] + [("bound", ctypes.c_int)]

    class Tube(ctypes.Structure):
        _fields_ = [("parameters", Parameters), ("bound", real * m),
                    ("members", ctypes.c_int * m), ("n_multi", ctypes.c_int),
                    ("multi", ctypes.c_int * m), ("n_segments", ctypes.c_int),
                    ("segments", Segment * capacity.segments), ("n_windows", ctypes.c_int),
                    ("windows", Window * capacity.windows)]

    return Tube


@lru_cache(maxsize=None)
def active_struct(n: int) -> type:
    """The ``ctypes`` layout of ``<P>_active`` (double), state dimension ``n``.

    Parameters
    ----------
    n : int
        State dimension.

    Returns
    -------
    type
        A ``ctypes.Structure`` subclass: ``tube`` (a pointer), ``start``, ``alpha``
        (``2 n``), ``switches``, ``refusal``, ``tube_check``, ``error``.
    """
    class Active(ctypes.Structure):
        _fields_ = [("tube", ctypes.c_void_p), ("start", ctypes.c_double),
                    ("alpha", ctypes.c_double * (2 * n)), ("switches", ctypes.c_int),
                    ("refusal", ctypes.c_int), ("tube_check", ctypes.c_int),
                    ("error", ctypes.c_double)]

    return Active


def pack_tube(design: TubeDesign, capacity: TubeCapacity, precision: str = "double"):
    """A tube as the ``<P>_tube_data`` struct of the generated C: what a companion computer
    sends (``bytes(pack_tube(...))``, the C layout of this machine's ABI; an Arm EABI
    target with 4-byte ``int`` lays it out the same, as the Cortex-M4F test shows).

    Parameters
    ----------
    design : TubeDesign
        The tube (its dimension the controller's).
    capacity : TubeCapacity
        The generated C's capacity.
    precision : {"double", "single"}, optional
        The generated C's real type.

    Returns
    -------
    ctypes.Structure
        A :func:`tube_struct` instance, in the order of the tables
        (:func:`~stt_codegen.codegen.tables.design_table_rows`), rows past the counts 0.

    Raises
    ------
    SpecError
        The tube does not fit the capacity (field ``tube_data``).

    Examples
    --------
    >>> import stt_codegen as stt
    >>> from stt_codegen.codegen.tube_data import TubeCapacity
    >>> from stt_codegen.runtime.data_controller import pack_tube
    >>> design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    >>> tube = pack_tube(design.tube, TubeCapacity(8, 32), "single")
    >>> tube.n_segments, tube.n_windows, len(bytes(tube))
    (1, 1, 1608)
    """
    require_capacity(design, capacity)
    tables = design_table_rows(design, float, precision == "single")
    tube = tube_struct(design.dimension, capacity,
                       ctypes.c_float if precision == "single" else ctypes.c_double)()
    for field, value, _ in tables.parameters:
        setattr(tube.parameters, field, value)
    tube.bound[:] = tables.bounds
    tube.members[:] = tables.members
    tube.n_multi = len(tables.multi)
    tube.multi[:len(tables.multi)] = tables.multi
    tube.n_segments = len(tables.segments)
    for j, row in enumerate(tables.segments):
        s = tube.segments[j]
        s.start, s.end, s.profile = row["start"], row["end"], row["profile"]
        s.from_[:], s.to[:] = row["from"], row["to"]
    tube.n_windows = len(tables.windows)
    for j, row in enumerate(tables.windows):
        w = tube.windows[j]
        for name in ("start", "end", "center", "radius", "sharpness", "height", "max_end"):
            setattr(w, name, row[name])
        w.bound = row["bound"]
    return tube


class TubeDataController:
    """The generated C (double) of a spec with the tube as data, compiled once.

    Parameters
    ----------
    design : TubeDesign
        The spec's tube: its dimension, actuator bound and state space fix the generated
        code; its own tube is ``<P>_design_tube``.
    capacity : TubeCapacity, optional
        The sizes of the tube's arrays; default 8 segments and 32 windows, or more when
        the design has more.
    look_ahead : LookAhead, optional
        A differential-drive base's axle offset and limits: the look-ahead variant's C
        (:func:`~stt_codegen.codegen.look_ahead_source.look_ahead_c_files`), whose step
        takes the base's state ``(x, y, theta)`` and writes ``(v, omega)``, and whose switch
        tests the look-ahead point; default law (13)'s C.

    Raises
    ------
    MissingTool, CodegenError
        No C compiler, or it failed.
    """

    name = "c"

    def __init__(self, design: TubeDesign, capacity: TubeCapacity | None = None,
                 look_ahead: LookAhead | None = None) -> None:
        capacity = capacity or fitting_capacity(design)
        spec = DesignSpec(design)
        prefix = spec.c_name
        if look_ahead is None:
            files = generate_files(spec, design, Options(("c",), "double", capacity))
            sources = {k: v for k, v in files.items() if k in (f"{prefix}.c", f"{prefix}.h")}
            # the measured state and the command: the tube's coordinates
            self.n_state = self.n_input = design.dimension
        else:
            sources = {k: v.encode() for k, v in look_ahead_c_files(
                design, look_ahead, prefix, "double", capacity=capacity).items()}
            self.n_state, self.n_input = 3, 2          # (x, y, theta) and (v, omega)
        self._lib = ctypes.CDLL(str(build_shared(sources, f"{prefix}.c")))
        self.n, self.capacity, self.design = design.dimension, capacity, design
        self.struct = tube_struct(self.n, capacity)
        ptr, real, integer = (ctypes.POINTER(ctypes.c_double), ctypes.c_double,
                              ctypes.c_int)
        tube_p = ctypes.POINTER(self.struct)
        self.design_tube = self.struct.in_dll(self._lib, f"{prefix}_design_tube")
        self.active = active_struct(self.n)
        active_p = ctypes.POINTER(self.active)
        self.functions = {}
        for name, args, result in (
                ("step", [tube_p, ptr, real, real, ptr, ptr, ptr], integer),
                ("tube_check", [tube_p], integer),
                ("active_init", [active_p], None),
                ("switch", [active_p, tube_p, real, ptr, real], integer),
                ("run", [active_p, ptr, real, real, ptr], integer)):
            f = getattr(self._lib, f"{prefix}_{name}")
            f.argtypes, f.restype = args, result
            self.functions[name] = f
        # the step's arrays and their pointers, made once: x, alpha, u, alpha_next
        self._arrays = [np.zeros(size) for size in (self.n_state, 2 * self.n, self.n_input,
                                                    2 * self.n)]
        self._pointers = [v.ctypes.data_as(ptr) for v in self._arrays]

    def pack(self, design: TubeDesign):
        """``design`` as a ``<P>_tube_data`` of this library (:func:`pack_tube`).

        Raises
        ------
        SpecError
            The tube does not fit the capacity (field ``tube_data``).
        """
        return pack_tube(design, self.capacity)

    def check(self, tube) -> int:
        """``<P>_tube_check`` of a packed tube (``0``: well formed)."""
        return int(self.functions["tube_check"](ctypes.byref(tube)))

    def load(self, design: TubeDesign) -> "_Loaded":
        """A controller running ``design``'s tube (packed, checked) on this library.

        Raises
        ------
        SpecError
            The tube does not fit the capacity, or ``<P>_tube_check`` refuses it (field
            ``tube_data``).
        """
        from ..errors import SpecError
        tube = self.pack(design)
        code = self.check(tube)
        if code != 0:
            raise SpecError("tube_data", f"the generated C's tube check refused the tube "
                                         f"(code {code}, docs/sensing.md)")
        return _Loaded(self, tube)


class _Loaded:
    """``step(x, t, dt, alpha) -> (u, alpha_next, status)`` of one packed tube."""

    name = "c"

    def __init__(self, owner: TubeDataController, tube) -> None:
        self.owner, self.tube = owner, tube

    def step(self, x, t, dt, alpha):
        o = self.owner
        xs, a, u, nxt = o._arrays
        xs[:] = np.reshape(x, o.n_state)
        a[:] = np.reshape(alpha, 2 * o.n)
        u.fill(0.0)
        nxt.fill(0.0)
        px, pa, pu, pn = o._pointers
        status = o.functions["step"](ctypes.byref(self.tube), px, t, dt, pa, pu, pn)
        return u.copy(), nxt.copy(), int(status)

    def switch_error(self, x) -> float:
        """``max_i |e_i|`` of the state ``x`` in this tube at its ``t = 0`` (``alpha = 0``),
        as the generated ``P_switch`` computes it; ``inf`` where it refuses for another
        reason (a state that is not finite)."""
        o = self.owner
        scratch = o.active()
        o.functions["active_init"](ctypes.byref(scratch))
        xs = np.ascontiguousarray(np.reshape(x, o.n_state), dtype=float)
        code = o.functions["switch"](ctypes.byref(scratch), ctypes.byref(self.tube), 0.0,
                                     xs.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), 0.0)
        return float(scratch.error) if code in (0, 4) else math.inf


def first_order_data_controller(design) -> TubeDataController:
    """Law (13)'s C with the tube as data for ``design`` (a Design; the variant's role
    ``data_controller``)."""
    return TubeDataController(design.tube)


def look_ahead_data_controller(design) -> TubeDataController:
    """The look-ahead variant's C with the tube as data for a differential-drive
    ``design`` (its axle offset and limits; the variant's role ``data_controller``)."""
    return TubeDataController(design.tube, look_ahead=design.look_ahead)


def no_data_controller(design) -> TubeDataController:
    """The role ``data_controller`` of a variant whose C takes no tube as data.

    Raises
    ------
    SpecError
        Always (field ``tube_data``, :func:`~stt_codegen.codegen.tube_data.require_tube_data`).
    """
    from ..codegen.tube_data import require_tube_data
    require_tube_data(design.spec)
    raise AssertionError("require_tube_data refuses every variant without a C tube as data")
