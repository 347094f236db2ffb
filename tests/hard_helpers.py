"""Helpers of the hardening tests: a small TOML writer and random plants (the hostile-input
tests, tests/test_hard_*.py), and :class:`HardCase`, what the suites over the generated API
need of each controller variant (see "the variants" below)."""

from __future__ import annotations

import json
import math
import re
import tomllib
from importlib import resources
from pathlib import Path
from typing import NamedTuple

import numpy as np


def toml_value(value) -> str:
    """One TOML value (inline tables and arrays; NaN and infinities as TOML spells them)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {toml_value(v)}"
                               for k, v in value.items()) + "}"
    raise TypeError(type(value))


def dumps(doc: dict) -> str:
    """A TOML document of top-level ``key = value`` lines."""
    return "".join(f"{json.dumps(str(k))} = {toml_value(v)}\n" for k, v in doc.items())


def bundled_doc(name: str) -> dict:
    data = resources.files("stt_codegen.cases").joinpath(name + ".toml").read_bytes()
    return tomllib.loads(data.decode())


def shape_docs() -> list[dict]:
    """The bundled specs, plus variants with a ball and a polytope obstacle (with tolerance)."""
    docs = [bundled_doc(f"omnirobot-s{k}") for k in (1, 2, 3)]
    ball = bundled_doc("omnirobot-s1")
    ball["obstacles"].append({"center": [3.5, 3.8], "radius": 0.3, "tolerance": 0.1})
    poly = bundled_doc("omnirobot-s2")
    poly["obstacles"].append({"vertices": [[3.2, 3.8], [3.9, 3.8], [3.5, 4.3]],
                              "tolerance": 0.08})
    poly3 = bundled_doc("omnirobot-s3")
    poly3["obstacles"].append({"vertices": [[2.8, 3.8, -0.5], [3.4, 3.8, -0.5],
                                            [3.0, 4.2, -0.5], [3.0, 4.0, 0.5]],
                               "dims": [0, 1, 2], "tolerance": 0.2})
    return docs + [ball, poly, poly3]


# --------------------------------------------------------------------------- unknown plants


def _skew(v):
    """A unit skew-symmetric matrix: the rotation generator in 2-D, ``v x`` in 3-D."""
    import numpy as np
    if len(v) == 2:
        return np.array([[0.0, -1.0], [1.0, 0.0]])
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def random_plant_parameters(rng, f_amp: float, f_lin: float, g_min: float, g_max: float,
                            skew: float, w_amp: float, n: int = 3) -> dict:
    """Parameters of ``x_dot = f(x) + g(x) u + w(t)`` (see :func:`unknown_plant`), seeded.

    ``f(x) = f_amp sin(W x + phi) + f_lin L (x - c) / |L|``: a bounded smooth term and a
    linear term about the state space's middle ``c`` (``|f_lin L/|L||`` is the spectral norm).
    ``g(x) = D + S + K(x)``: ``D + S`` symmetric with eigenvalues in ``[g_min, g_max]``,
    ``K(x) = skew * tanh(v . x) * skew-matrix``, skew-symmetric (so the symmetric part of g
    has ``lambda_min >= g_min``, uniformly in x). ``w_i(t) = w_amp sin(omega_i t + p_i)``.
    """
    import numpy as np
    q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    eig = rng.uniform(g_min, g_max, n)
    eig[0], eig[-1] = g_min, g_max                      # the extremes are attained
    sym = q @ np.diag(eig) @ q.T
    lin = rng.normal(size=(n, n))
    lin = lin / np.linalg.norm(lin, 2)
    axis = rng.normal(size=n)
    return {"W": rng.normal(size=(n, n)), "phi": rng.uniform(0, 2 * np.pi, n), "f_amp": f_amp,
            "L": f_lin * lin, "sym": sym, "skew_axis": axis / np.linalg.norm(axis),
            "skew": skew, "v": rng.normal(size=n), "w_amp": w_amp,
            "omega": rng.uniform(0.2, 5.0, n), "w_phase": rng.uniform(0, 2 * np.pi, n)}


def unknown_plant(p: dict, centre):
    """A python-control ``NonlinearIOSystem`` (n states, inputs and outputs) from parameters."""
    import control as ct
    import numpy as np
    centre = np.asarray(centre, float)
    k_mat = _skew(p["skew_axis"])

    def rhs(t, x, u, params):
        f = p["f_amp"] * np.sin(p["W"] @ x + p["phi"]) + p["L"] @ (x - centre)
        g = p["sym"] + p["skew"] * np.tanh(p["v"] @ x) * k_mat
        w = p["w_amp"] * np.sin(p["omega"] * t + p["w_phase"])
        return f + g @ u + w

    n = len(centre)
    return ct.nlsys(rhs, None, inputs=n, states=n, outputs=n)


def plant_bounds(p: dict, spec) -> dict:
    """Bounds of the drawn plant over the state space: ``|f|_inf``, ``lambda_min`` and
    ``lambda_max`` of the symmetric part of g, and ``|g|_2`` (upper bound)."""
    import numpy as np
    lo, hi = np.array(spec.state_space.lower), np.array(spec.state_space.upper)
    centre = (lo + hi) / 2
    f_bound = p["f_amp"] + np.max(np.abs(p["L"]) @ ((hi - lo) / 2))
    eig = np.linalg.eigvalsh(p["sym"])
    return {"f_inf": float(f_bound), "g_sym_min": float(eig[0]), "g_sym_max": float(eig[-1]),
            "g_norm": float(eig[-1] + p["skew"]), "w_inf": p["w_amp"], "centre": centre}


# --------------------------------------------------------------------------- the variants
#
# What the hardening suites (tests/test_hard_generated_api.py, test_codegen_misra.py,
# test_codegen_fenv.py, test_codegen_null_outputs.py, test_codegen_status_boundary.py,
# test_codegen_large_coordinates.py) need of a controller variant, in one place: its
# bundled case, its generated files, the sizes, limits and status codes of its header, the
# API functions the header declares (parsed from their prototypes) and the state whose
# tube point is a given point. The suites are written once against :class:`HardCase`.

#: The bundled case of each controller variant the suites run on (``spec.variant``); the
#: differential drive's is the first bundled ``look-ahead`` case, else the test spec below.
VARIANT_CASES = {"first-order": "omnirobot-s1", "cascade": "second-order-s1",
                 "look-ahead": None}
#: The differential-drive spec used while no bundled case is of that variant.
LOOK_AHEAD_FALLBACK = "office-drive"
#: Outputs the header allows to be NULL (not written), all other pointers are required.
OPTIONAL_OUTPUTS = frozenset({"gamma_L_dot", "gamma_U_dot"})


def _bundled_names() -> list[str]:
    return sorted(p.name[:-5] for p in resources.files("stt_codegen.cases").iterdir()
                  if p.name.endswith(".toml"))


def look_ahead_case() -> str:
    """The differential-drive case: a bundled one if any, else ``tests/specs/office-drive``."""
    from stt_codegen.spec.loader import load_spec
    for name in _bundled_names():
        if bundled_doc(name).get("plant", {}).get("model") == "differential-drive":
            if load_spec(name).variant == "look-ahead":
                return name
    return str(Path(__file__).parent / "specs" / f"{LOOK_AHEAD_FALLBACK}.toml")


def case_of(variant: str) -> str:
    """The case (bundled name or spec path) the suites run ``variant`` on."""
    return VARIANT_CASES[variant] or look_ahead_case()


class Argument(NamedTuple):
    """One parameter of a generated C function: ``kind`` is ``scalar``, ``in`` or ``out``;
    ``size`` the header macro of an array's length (without the prefix), else ``None``."""

    name: str
    kind: str
    size: str | None


def prototypes(header: str, prefix: str) -> dict[str, list[Argument]]:
    """The API functions a generated header declares: ``{"step": [Argument, ...], ...}``.

    Parsed from the prototypes ``int P_name(...);`` (every API function returns a status);
    ``const P_real a[P_SIZE]`` is an input array, ``P_real a[P_SIZE]`` an output,
    ``P_real a`` a scalar.
    """
    out = {}
    for name, params in re.findall(rf"^int {prefix}_(\w+)\(([^;]*)\);", header, re.M):
        args = []
        for param in params.split(","):
            m = re.fullmatch(rf"\s*(const )?{prefix}_real (\w+)(?:\[{prefix.upper()}_(\w+)\])?\s*",
                             param)
            assert m, f"unparsed parameter of {prefix}_{name}: {param!r}"
            kind = "scalar" if m.group(3) is None else ("in" if m.group(1) else "out")
            args.append(Argument(m.group(2), kind, m.group(3)))
        out[name] = args
    assert "step" in out and "tube" in out, sorted(out)
    return out


def header_macros(header: str, prefix: str) -> dict[str, float]:
    """The numeric ``#define P_NAME value`` of a header, by ``NAME``."""
    return {k: float(v) for k, v in re.findall(
        rf"^#define {prefix.upper()}_(\w+) ([-+0-9.eE]+)\s*$", header, re.M)}


def _point_state(case, point):
    return np.asarray(point, float)


def _cascade_state(case, point):
    """Positions at ``point``, velocities 0."""
    return np.concatenate([np.asarray(point, float), np.zeros(case.n)])


def _look_ahead_state(case, point):
    """The base state ``(x, y, theta)`` whose look-ahead point is ``point``, heading 0:
    ``(point_0 - l, point_1, 0)`` (the C computes ``x + l cos 0 = x + l``, rounded)."""
    offset = case.design.stage.axle_offset
    return np.array([point[0] - offset, point[1], 0.0])


def _look_ahead_point(case, state):
    offset = case.design.stage.axle_offset
    return np.array([state[0] + offset * np.cos(state[2]), state[1] + offset * np.sin(state[2])])


def _exact_point_state(case, point, dtype, velocity):
    return np.asarray(point, dtype)


def _exact_cascade_state(case, point, dtype, velocity):
    """Positions at ``point``, velocities the virtual velocity ``r`` there (``velocity(x)``
    computes it in the code under test): the velocity error ``x2 - r`` is exactly 0."""
    x = np.concatenate([np.asarray(point, dtype), np.zeros(case.n, dtype)])
    x[case.n:] = velocity(x)
    return x


def _exact_look_ahead_state(case, point, dtype, velocity):
    """``(x, point_1, 0)`` with ``x + l == point_0`` exactly in ``dtype`` (heading 0: the
    code computes ``p = (x + l cos 0, y + l sin 0) = (x + l, y)``); ``None`` when no ``x``
    within 4 ulps of ``point_0 - l`` rounds there."""
    offset = dtype(case.design.stage.axle_offset)
    target = dtype(point[0])
    start = dtype(target - offset)
    for k in range(9):
        x = start
        for _ in range(k // 2 + k % 2):
            x = np.nextafter(x, dtype(np.inf) if k % 2 else dtype(-np.inf), dtype=dtype)
        if dtype(x + offset) == target:
            return np.array([x, point[1], 0.0], dtype)
    return None


#: Per variant: hostile states beyond those of :meth:`HardCase.state_at` (the cascade's
#: velocities far outside the velocity tube, to reach OUTSIDE_VELOCITY_TUBE).
EXTRA_STATES = {"first-order": lambda case, point: [],
                "cascade": lambda case, point: [
                    np.concatenate([np.asarray(point, float), np.full(case.n, 1e3)])],
                "look-ahead": lambda case, point: []}
#: Per variant: a state whose tube point is a given point exactly in a given precision,
#: with the velocity error 0 where there is one (:meth:`HardCase.exact_state`).
EXACT_STATE = {"first-order": _exact_point_state, "cascade": _exact_cascade_state,
               "look-ahead": _exact_look_ahead_state}
def _first_order_step(case):
    from stt_codegen.tube.model import build_model
    return build_model(case.tube)["controller_step"]


def _cascade_step(case):
    from stt_codegen.tube.cascade import cascade_step
    return cascade_step(case.tube, case.design.stage)


def _look_ahead_step(case):
    from stt_codegen.tube.look_ahead import look_ahead_step
    return look_ahead_step(case.tube, case.design.stage)


#: Per variant: the CasADi step the generated code is printed from.
CASADI_STEP = {"first-order": _first_order_step, "cascade": _cascade_step,
               "look-ahead": _look_ahead_step}
#: Per variant: a state whose tube point (the point the tube must hold) is a given point,
#: and the tube point of a state.
STATE_AT = {"first-order": _point_state, "cascade": _cascade_state,
            "look-ahead": _look_ahead_state}
POINT_OF = {"first-order": lambda case, x: np.asarray(x, float),
            "cascade": lambda case, x: np.asarray(x[:case.n], float),
            "look-ahead": _look_ahead_point}


class HardCase:
    """One controller variant on its case, as the hardening suites see it.

    Attributes: ``variant``, ``case`` (the name given to :func:`conftest.design_of`),
    ``design`` (the :class:`~stt_codegen.design.result.Design`), ``tube`` (its
    :class:`~stt_codegen.tube.parameters.TubeDesign`), ``n`` (the tube's dimension).
    """

    def __init__(self, variant: str, case: str | None = None) -> None:
        from conftest import design_of
        self.variant = variant
        self.case = case or case_of(variant)
        self.design = design_of(self.case)
        assert self.design.spec.variant == variant, (self.case, self.design.spec.variant)
        self.tube = self.design.tube
        self.n = self.tube.dimension
        self._files: dict = {}

    def __repr__(self) -> str:
        return f"HardCase({self.variant!r}: {self.case})"

    def files(self, precision: str = "double") -> dict[str, bytes]:
        """Every generated file (C and Python) in ``precision``, cached."""
        if precision not in self._files:
            from stt_codegen.codegen.api import design_files
            from stt_codegen.codegen.options import Options
            self._files[precision] = design_files(self.design, Options(("c", "python"),
                                                                       precision))
        return self._files[precision]

    @property
    def prefix(self) -> str:
        """``P``: the generated files are ``P.h``, ``P.c``, ..."""
        (name,) = [k[:-2] for k in self.files() if k.endswith(".h")]
        return name

    @property
    def header(self) -> str:
        return self.files()[f"{self.prefix}.h"].decode()

    @property
    def macros(self) -> dict[str, float]:
        """The header's numeric macros: sizes (``N``, ``N_STATE``, ``N_INPUT``,
        ``N_ALPHA``), limits (``DT_MIN``, ``DT_MAX``, ``ALPHA_MAX``), status codes."""
        return header_macros(self.header, self.prefix)

    def size(self, name: str) -> int:
        """A length macro of the header (``N``, ``N_STATE``, ``N_INPUT``, ``N_ALPHA``)."""
        return int(self.macros[name])

    @property
    def statuses(self) -> dict[str, int]:
        """``{"OK": 0, "OUTSIDE_TUBE": 1, ...}``: the status codes the header defines."""
        return {k[len("STATUS_"):]: int(v) for k, v in self.macros.items()
                if k.startswith("STATUS_")}

    @property
    def functions(self) -> dict[str, list[Argument]]:
        """The API functions the header declares, with their parameters."""
        return prototypes(self.header, self.prefix)

    def vectors(self, precision: str) -> dict[str, list]:
        """The inputs of the shipped test vectors (``P_vectors.json``): ``x``, ``t``,
        ``dt``, ``alpha``, one entry per vector (columns, or rows under ``vectors`` with
        one ``dt`` for all)."""
        data = json.loads(self.files(precision)[f"{self.prefix}_vectors.json"])
        if "vectors" not in data:
            return {k: data[k] for k in ("x", "t", "dt", "alpha")}
        rows = data["vectors"]
        return {"x": [r["x"] for r in rows], "t": [r["t"] for r in rows],
                "dt": [r.get("dt", data.get("dt")) for r in rows],
                "alpha": [r["alpha"] for r in rows]}

    def python(self):
        """The generated Python module (double)."""
        from stt_codegen.runtime.compiled import load_python_module
        return load_python_module(self.files()[f"{self.prefix}.py"], self.prefix)

    def state_at(self, point):
        """A state (``N_STATE``,) whose tube point is ``point`` (n,)."""
        return STATE_AT[self.variant](self, point)

    def extra_states(self, point) -> list:
        """Hostile states the variant adds at a tube point (the cascade: velocities of
        1e3, far outside its velocity tube)."""
        return EXTRA_STATES[self.variant](self, point)

    def exact_state(self, point, dtype, velocity=None):
        """A state (``N_STATE``,) in ``dtype`` whose tube point, as the generated code
        computes it in that precision, is ``point`` exactly; any velocity error is 0
        (``velocity(x)``: the cascade's virtual velocity at ``x``, by the code under
        test). ``None`` if the variant cannot place that point exactly."""
        return EXACT_STATE[self.variant](self, point, dtype, velocity)

    def casadi_step(self):
        """The variant's CasADi step ``(x, t, dt, alpha) -> (u, alpha_next, ...)``, whose
        ``inside*`` outputs are 1.0 exactly when the status is OK."""
        return CASADI_STEP[self.variant](self)

    def point_of(self, state):
        """The tube point (n,) of a state (``N_STATE``,), in double."""
        return POINT_OF[self.variant](self, state)


VARIANTS = tuple(VARIANT_CASES)
_CASES: dict[tuple, HardCase] = {}


def hard_case(variant: str, case: str | None = None) -> HardCase:
    """The :class:`HardCase` of a variant (on its case of :data:`VARIANT_CASES`, or on
    ``case``), built once per session."""
    if (variant, case) not in _CASES:
        _CASES[variant, case] = HardCase(variant, case)
    return _CASES[variant, case]


def variant_params(fast=("first-order",)):
    """``pytest.param`` of each variant: those in ``fast`` in the fast tier, the others
    marked ``slow`` (their designs and builds are the expensive part)."""
    import pytest
    return [pytest.param(v, id=v, marks=() if v in fast else pytest.mark.slow)
            for v in VARIANTS]


class CApi:
    """ctypes view of a compiled generated library, its functions from the header.

    ``call(name, **arrays_and_scalars)`` calls ``P_name`` with each parameter by name (an
    array, a scalar, or ``None`` for a NULL pointer) and returns the status.
    """

    def __init__(self, path, case: HardCase, precision: str) -> None:
        import ctypes
        self.case = case
        self.lib = ctypes.CDLL(str(path))
        self.real = ctypes.c_double if precision == "double" else ctypes.c_float
        self.dtype = np.float64 if precision == "double" else np.float32
        self.functions = case.functions
        self._pointer = ctypes.POINTER(self.real)
        for name, args in self.functions.items():
            fn = getattr(self.lib, f"{case.prefix}_{name}")
            fn.argtypes = [self.real if a.kind == "scalar" else self._pointer for a in args]
            fn.restype = ctypes.c_int

    def arr(self, values=None, size=None):
        """A contiguous array in the library's precision (zeros of ``size`` if no values)."""
        if values is None:
            return np.zeros(size, self.dtype)
        return np.ascontiguousarray(np.asarray(values, dtype=self.dtype))

    def nan(self, size: str):
        """An output buffer of the header length ``size`` filled with NaN."""
        return self.arr(np.full(self.case.size(size), math.nan))

    def call(self, name: str, **given) -> int:
        args = []
        for a in self.functions[name]:
            value = given[a.name]
            if a.kind == "scalar":
                args.append(float(value))
            elif value is None:
                args.append(None)
            else:
                assert value.dtype == self.dtype and value.flags.c_contiguous
                args.append(value.ctypes.data_as(self._pointer))
        return int(getattr(self.lib, f"{self.case.prefix}_{name}")(*args))


def c_api(case: HardCase, precision: str, cc: str, root) -> CApi:
    """Write, compile (strict warnings, ``-Werror``) and load the C of ``case`` (cached)."""
    from codegen_helpers import compile_shared, write
    key = (case.variant, case.case, precision, cc, str(root))
    if key not in _LIBS:
        folder = write(Path(root) / f"{case.prefix}-{precision}-{cc}",
                       {k: v for k, v in case.files(precision).items() if k.endswith((".c", ".h"))
                        and not k.endswith("_selftest.c")})
        _LIBS[key] = CApi(compile_shared(folder, case.prefix, cc, precision), case, precision)
    return _LIBS[key]


_LIBS: dict = {}
