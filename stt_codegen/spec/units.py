"""Values that are valid but look like a unit mistake: warned about at loading
(:class:`~stt_codegen.errors.UnitWarning`), never refused."""

from __future__ import annotations

import warnings

from ..errors import UnitWarning, number_text

__all__ = ["unit_warnings", "warn_units"]


def unit_warnings(spec) -> list[tuple[str, str]]:
    """The fields of a loaded spec that look like a unit mistake, with the reason.

    A rate below 1 Hz (kHz meant); a length larger than the state space's largest extent
    (millimetres meant where the state space is in metres): ``robot.radius``,
    ``plant.axle_offset``, ``plant.track_width``, ``plant.wheel_radius``. An angle beyond
    pi (``initial.heading``, degrees meant) is an error of the loader, not a warning.
    """
    found = []
    if spec.rate_hz < 1.0:
        found.append(("controller.rate_hz", f"{number_text(spec.rate_hz)} Hz is below 1 Hz "
                                            f"(a rate meant in kHz? 1 kHz is 1000)"))
    space = spec.robot.state_space if spec.robot is not None else spec.state_space
    extent = max(hi - lo for lo, hi in zip(space.lower, space.upper))
    # each length where the spec has it (None where it has no robot, no base, no wheels)
    lengths = [("robot.radius", getattr(spec.robot, "radius", None))]
    lengths += [(f"plant.{key}", getattr(spec.drive, key, None))
                for key in ("axle_offset", "track_width", "wheel_radius")]
    for name, value in lengths:
        if value is not None and value > extent:
            found.append((name, f"{number_text(value)} is larger than the state space "
                                f"({number_text(extent)} across at most): a length in "
                                f"millimetres where the state space is in metres?"))
    return found


def warn_units(spec) -> None:
    """Warn (:class:`~stt_codegen.errors.UnitWarning`) for each of :func:`unit_warnings`."""
    for name, reason in unit_warnings(spec):
        warnings.warn(UnitWarning(f"{name}: {reason}"), stacklevel=3)
