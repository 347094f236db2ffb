"""The tube as data: the generated C whose tube is an argument, replaced at run time.

With a :class:`TubeCapacity` the generated C (first order) keeps no tube in ``const``
tables: every function takes a ``const <P>_tube_data*`` (the parameters, state-space bounds,
reach segments and circumvent windows of one tube, in the tables' order, up to the
capacity's counts), ``<P>_tube_check`` says whether a tube is well formed, and
``<P>_switch`` / ``<P>_run`` change the active tube at a sample where the state lies in the
new one (docs/sensing.md, "The tube as data"). The bodies are the same pieces as the
tables' code, composed the same way, so a tube run as data computes what the CasADi model
of that tube computes, bit for bit in double precision.

This module holds what the template needs to print either form: the names of the tables
(:func:`table_names`) and which code paths are emitted (:func:`table_shape`).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import SpecError
from ..tube.parameters import GLIDE, SCURVE, TubeDesign
from ..tube.pieces import PROFILE_NAMES
from .tables import PARAMETERS, Tables

__all__ = ["DATA_PROFILES", "DEFAULT_CAPACITY", "TubeCapacity", "TableShape",
           "fitting_capacity", "parse_capacity", "profile_codes", "python_names",
           "require_capacity", "require_tube_data", "table_names", "table_shape"]


@dataclass(frozen=True)
class TubeCapacity:
    """How large a tube the data form holds: the sizes of ``<P>_tube_data``'s arrays.

    Attributes
    ----------
    segments : int
        Reach segments of eq. (4) (``<P>_MAX_SEGMENTS``), at least 1.
    windows : int
        Circumvent windows of eqs. (7)-(9) (``<P>_MAX_WINDOWS``), at least 1; also the size
        of the work arrays of the open windows.

    Raises
    ------
    SpecError
        A count below 1 or above 4096 (field ``tube_data``).

    Examples
    --------
    >>> from stt_codegen.codegen.tube_data import TubeCapacity
    >>> TubeCapacity(8, 32)
    TubeCapacity(segments=8, windows=32)
    """

    segments: int = 8
    windows: int = 32

    def __post_init__(self) -> None:
        for name in ("segments", "windows"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 4096:
                raise SpecError("tube_data", f"{name} must be a whole number from 1 to 4096, "
                                             f"got {value!r}")

    def to_json(self) -> dict:
        return {"segments": self.segments, "windows": self.windows}


#: The capacity of ``--tube-data`` without numbers.
DEFAULT_CAPACITY = TubeCapacity()


def fitting_capacity(design: TubeDesign) -> TubeCapacity:
    """:data:`DEFAULT_CAPACITY`, or more where ``design`` has more segments or windows:
    the capacity of a host-side controller that runs the design's tubes.

    Parameters
    ----------
    design : TubeDesign

    Returns
    -------
    TubeCapacity
    """
    return TubeCapacity(max(DEFAULT_CAPACITY.segments, len(design.segments)),
                        max(DEFAULT_CAPACITY.windows, len(design.circumvents)))


def parse_capacity(text: str) -> TubeCapacity:
    """``"SEGMENTS,WINDOWS"`` (``--tube-data``) as a capacity.

    Parameters
    ----------
    text : str
        Two whole numbers separated by a comma.

    Returns
    -------
    TubeCapacity

    Raises
    ------
    SpecError
        Not two whole numbers from 1 to 4096 (field ``tube_data``).

    Examples
    --------
    >>> from stt_codegen.codegen.tube_data import parse_capacity
    >>> parse_capacity("4,16")
    TubeCapacity(segments=4, windows=16)
    """
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) != 2 or not all(p.isdigit() for p in parts):
        raise SpecError("tube_data", f"expected SEGMENTS,WINDOWS (two whole numbers), got "
                                     f"{text!r}")
    return TubeCapacity(int(parts[0]), int(parts[1]))


@dataclass(frozen=True)
class TableShape:
    """Which code paths the composition emits.

    Attributes
    ----------
    windows : bool
        Some circumvent window exists (the open-window search and ``bump``).
    single : bool
        Some bound has exactly one circumvent (``fnu_single``).
    multi : bool
        Some bound has several (``F_nu``).
    profiles : list of str
        The reach profiles whose bodies are called.
    blended : bool
        The next segment's move is added where it has started (blended corners; always in
        the data form, whose tube may blend: a tube that does not never enters the path).
    """

    windows: bool
    single: bool
    multi: bool
    profiles: list
    blended: bool = False


def table_names(prefix: str, data: bool) -> dict[str, str]:
    """The C text of each table the composition reads, and of the tube argument.

    Parameters
    ----------
    prefix : str
        The C prefix.
    data : bool
        The tube is data (``tube->...``), else the ``const`` tables (``<P>_...``).

    Returns
    -------
    dict of str to str
        ``parameters``, ``bound``, ``members``, ``n_multi``, ``multi``, ``segments``,
        ``n_segments``, ``windows``, ``n_windows``; ``arg`` (the parameter that starts
        every function's list), ``call`` (the argument that starts every call),
        ``usable`` (the first test of a public function's input check) and ``design``
        (the first argument of a call on the spec's own tube), empty for tables;
        ``cleared``: how many entries of the open windows' work arrays are cleared
        (``MAX_OPEN``; the tube's windows for the data form, as no more can be open).
    """
    fields = ("parameters", "bound", "members", "n_multi", "multi", "segments", "n_segments",
              "windows", "n_windows")
    if not data:
        names = {f: f"{prefix.upper()}_{f.upper()}" for f in fields}
        return dict(names, arg="", call="", usable="", design="",
                    cleared=f"{prefix.upper()}_MAX_OPEN")
    names = {f: f"tube->{f}" for f in fields}
    return dict(names, arg=f"const {prefix}_tube_data* tube,\n    ", call="tube, ",
                usable=f"({prefix}_tube_usable(tube) != 0) && ",
                design=f"&{prefix}_design_tube, ", cleared="tube->n_windows")


def python_names(data: bool) -> dict[str, object]:
    """The Python text of each table the module's composition reads, and of the tube
    argument (:func:`table_names`' counterpart for ``python_module.py.j2``).

    Parameters
    ----------
    data : bool
        The tube is data (``tube.segments``, ...), else the module's tables
        (``SEGMENTS``, ...).

    Returns
    -------
    dict
        ``segments``, ``windows``, ``bound``, ``members`` and each parameter of
        :data:`~.tables.PARAMETERS` by its field name; ``arg`` (the parameter that starts
        the list of every function reading the tube), ``call`` (the argument that starts
        every call of one), ``usable`` (the first test of a public function's input check)
        and ``data``.
    """
    fields = ("segments", "windows", "bound", "members")
    if not data:
        return dict({f: f.upper() for f in fields},
                    **{f: f.upper() for f, _, _ in PARAMETERS},
                    arg="", call="", usable="", data=False)
    return dict({f: f"tube.{f}" for f in fields},
                **{f: f"tube.parameters.{f}" for f, _, _ in PARAMETERS},
                arg="tube, ", call="tube, ", usable="_usable(tube) and ", data=True)


#: The reach profiles a tube as data may use, coded as in ``PROFILE_NAMES`` (which lists
#: them first): those law (13)'s designs produce. The S-curve and the glide are the
#: cascade's (via points timed for a force), which has no tube as data; the S-curve's body
#: alone would cost 1.8 kB of Cortex-M4F flash. A segment of another profile fails the
#: data's check (code 5).
DATA_PROFILES = tuple(p for p in PROFILE_NAMES if p not in (SCURVE, GLIDE))


def profile_codes(capacity: TubeCapacity | None) -> dict[str, int]:
    """The segment table's profile codes the generated code knows: every profile's (of
    ``PROFILE_NAMES``) for the tables, :data:`DATA_PROFILES`' for the data form.

    Parameters
    ----------
    capacity : TubeCapacity or None
        The data form's capacity, or ``None`` for the tables.

    Returns
    -------
    dict of str to int
    """
    names = DATA_PROFILES if capacity is not None else PROFILE_NAMES
    return {name: k for k, name in enumerate(names)}


def table_shape(tables: Tables, capacity: TubeCapacity | None) -> TableShape:
    """The code paths of a design's tables, or every path for the data form.

    Parameters
    ----------
    tables : Tables
        The design's printed tables.
    capacity : TubeCapacity or None
        The data form's capacity, or ``None`` for the tables.

    Returns
    -------
    TableShape
    """
    if capacity is not None:
        return TableShape(True, True, True, list(DATA_PROFILES), True)
    return TableShape(bool(tables.windows), 1 in tables.members, bool(tables.multi),
                      list(tables.profiles), tables.blended)


def require_tube_data(spec, targets: tuple[str, ...] = ("c",)) -> None:
    """Refuse a spec whose controller variant has no tube as data for ``targets`` (the
    variant decides: ``ControllerVariant.tube_data``).

    Parameters
    ----------
    spec : Spec
        The spec to generate for.
    targets : tuple of str
        ``"c"``, ``"python"``, ``"embedded"``: where the tube as data is asked for.

    Raises
    ------
    SpecError
        Its variant does not take its tube as data in one of ``targets`` (field
        ``tube_data``).
    """
    from ..spec.variants import variant_of
    variant = variant_of(spec)
    missing = [t for t in targets if t not in variant.tube_data]
    if missing:
        where = (f"only in {', '.join(variant.tube_data)}" if variant.tube_data
                 else "in no language")
        raise SpecError("tube_data", f"the tube as data is not generated in "
                                     f"{', '.join(missing)} for {variant.plant_words}: the "
                                     f"{variant.name} variant takes its tube as data "
                                     f"{where} (docs/sensing.md, \"The tube as data\")")


def require_capacity(design: TubeDesign, capacity: TubeCapacity) -> None:
    """Refuse a capacity the design's own tube does not fit in.

    Parameters
    ----------
    design : TubeDesign
        The spec's tube (printed as ``<P>_design_tube``).
    capacity : TubeCapacity

    Raises
    ------
    SpecError
        More segments or circumvents than the capacity, or a segment profile outside
        :data:`DATA_PROFILES` (field ``tube_data``). A tube that blends corners
        (:attr:`~stt_codegen.tube.parameters.TubeDesign.blends_corners`) is taken: the data
        form adds the next segment's move where it has started, as the model does.
    """
    unknown = sorted({s.profile for s in design.segments} - set(DATA_PROFILES))
    if unknown:
        raise SpecError("tube_data", f"the tube has {', '.join(unknown)} segments; the "
                                     f"tube as data runs {', '.join(DATA_PROFILES)} ones")
    for name, count in (("segments", len(design.segments)),
                        ("windows", len(design.circumvents))):
        if count > getattr(capacity, name):
            raise SpecError("tube_data", f"the spec's tube has {count} {name}, more than the "
                                         f"capacity's {getattr(capacity, name)}")
