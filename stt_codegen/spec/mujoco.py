"""``[plant] model = "mujoco"``: the MuJoCo model a spec's plant is simulated on.

The spec names an MJCF file (relative to the spec file's folder), the slide or hinge joint
whose position is each state, the actuator that takes each input, and optionally MuJoCo's
timestep. The toolkit has no equations of such a plant: the design and ``verify`` use the
declared ``[assumptions]`` as they are, and nothing here proves the MJCF plant meets them
(docs/mujoco.md). Loading the file and finding the names needs MuJoCo
(:class:`~stt_codegen.runtime.mujoco_plant.MujocoPlant`); the loader checks only what it
can without it: the counts, and, for a spec read from a file, that the MJCF file exists.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from ..errors import SpecError

__all__ = ["MujocoModel", "mujoco_model", "with_folder"]


@dataclass(frozen=True)
class MujocoModel:
    """The MuJoCo model of a spec's plant (``[plant] model = "mujoco"``).

    Attributes
    ----------
    mjcf : str
        The MJCF file as the spec gives it (relative paths are to :attr:`folder`).
    joints : tuple of str
        One slide or hinge joint per state, in the spec's order.
    actuators : tuple of str
        One actuator per input, in the order of ``u``.
    timestep : float or None
        MuJoCo's timestep, s; ``None``: the model's own.
    folder : str or None
        The folder of the spec file (``None`` for a spec given as a dict: the working
        folder). Where the file is, not what the spec says: not compared, never written
        into generated files.
    """

    mjcf: str
    joints: tuple[str, ...]
    actuators: tuple[str, ...]
    timestep: float | None = None
    folder: str | None = field(default=None, compare=False)

    @property
    def path(self) -> Path:
        """The MJCF file: :attr:`mjcf` itself when absolute, else in :attr:`folder`."""
        given = Path(self.mjcf)
        return given if given.is_absolute() or self.folder is None else Path(self.folder) / given


def mujoco_model(table: Any, n: int, inputs: int) -> MujocoModel | None:
    """The MuJoCo model of a validated ``[plant]`` table whose model is ``"mujoco"``.

    Parameters
    ----------
    table : PlantTable
        The validated ``[plant]`` table.
    n : int
        State dimension.
    inputs : int
        Number of inputs ``u``.

    Returns
    -------
    MujocoModel

    Raises
    ------
    SpecError
        ``plant.mjcf``, ``plant.joints`` or ``plant.actuators`` missing, or a count other
        than ``n`` joints and ``inputs`` actuators.
    """
    for key in ("mjcf", "joints", "actuators"):
        if getattr(table, key) is None:
            raise SpecError(f"plant.{key}", "missing: a MuJoCo plant needs the MJCF file "
                                            "(mjcf), the joint of each state (joints) and the "
                                            "actuator of each input (actuators)")
    if len(table.joints) != n:
        raise SpecError("plant.joints", f"must name {n} joints (one per state), got "
                                        f"{len(table.joints)}")
    if len(table.actuators) != inputs:
        raise SpecError("plant.actuators", f"must name {inputs} actuators (one per input), "
                                           f"got {len(table.actuators)}")
    return MujocoModel(table.mjcf, tuple(table.joints), tuple(table.actuators), table.timestep)


def with_folder(spec: Any, folder: Path) -> Any:
    """``spec`` with its MuJoCo model's file resolved in ``folder`` (the spec file's), the
    file checked to exist; ``spec`` itself when it has no MuJoCo model.

    Parameters
    ----------
    spec : Spec
    folder : pathlib.Path
        The folder of the spec file.

    Returns
    -------
    Spec

    Raises
    ------
    SpecError
        Field ``plant.mjcf``: no such file.
    """
    if spec.mujoco is None:
        return spec
    model = replace(spec.mujoco, folder=str(folder))
    if not model.path.is_file():
        raise SpecError("plant.mjcf", f"no file {model.mjcf!r} (relative to the spec's "
                                      "folder)")
    return replace(spec, mujoco=model)
