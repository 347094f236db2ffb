"""A MuJoCo model as the plant of the closed loop: dynamics nobody here wrote.

The controller sees only the spec's states, read from the model's joints: for a
first-order spec the positions (``qpos`` of the named joints), for a second-order spec the
positions and then the velocities (``qvel`` of the same joints). Its inputs go to the
named actuators' ``ctrl`` (MuJoCo clamps them to a limited actuator's ``ctrlrange``, as
the hardware would). Between two samples the held input drives ``mj_step`` at the model's
timestep (``1 / rate_hz``, and a ``[controller] delay``, must be whole numbers of
timesteps: the previous input is then held for the delay, the new one for the rest of the
period). A contact of the robot with anything but a ground plane is recorded: the run
judges it like a collision.

``mujoco`` is a dependency of the package; this module imports it on first use and raises
a :class:`~stt_codegen.errors.SpecError` saying how to install it when it is absent.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import SpecError

__all__ = ["DriveMujocoPlant", "MujocoPlant", "require_mujoco"]


def require_mujoco():
    """The ``mujoco`` module.

    Returns
    -------
    module
        ``mujoco``.

    Raises
    ------
    SpecError
        Field ``plant.model``: MuJoCo is not installed (the message says how to install it).
    """
    try:
        import mujoco
    except ImportError:
        raise SpecError("plant.model", "a MuJoCo plant needs the mujoco package: "
                                       "pip install stt-codegen (or pip install "
                                       "mujoco)") from None
    return mujoco


class MujocoPlant:
    """A MuJoCo model stepped at its own timestep, with the input held between samples.

    Parameters
    ----------
    mjcf : str or pathlib.Path
        The model file (MJCF XML).
    joints : sequence of str
        One joint per position of the spec (a slide or hinge joint: one ``qpos`` and one
        ``qvel`` entry), in the spec's order.
    actuators : sequence of str
        One actuator per input, in the order of ``u``.
    order : {1, 2}
        1: the state is the joints' positions; 2: their positions, then their velocities.
    timestep : float, optional
        Overrides the model's ``opt.timestep``, s (default: the model's own).

    Attributes
    ----------
    nstates, ninputs : int
        ``order * len(joints)`` and ``len(actuators)``.
    timestep : float
        The timestep stepped, s.
    contact_count : int
        MuJoCo steps since :meth:`reset` with a contact of a non-ground geom pair.
    first_contact : tuple or None
        ``(t, geom1, geom2)`` of the first such contact (names, or ids where unnamed).

    Raises
    ------
    SpecError
        MuJoCo missing or the file unreadable (field ``plant.mjcf``), an unknown or
        multi-dimensional joint (``plant.joints``), an unknown actuator
        (``plant.actuators``), a bad ``order`` or ``timestep``.
    """

    def __init__(self, mjcf: str | Path, joints, actuators, order: int = 1,
                 timestep: float | None = None) -> None:
        mujoco = require_mujoco()
        self._mj = mujoco
        try:
            self.model = mujoco.MjModel.from_xml_path(str(mjcf))
        except (ValueError, OSError) as exc:
            raise SpecError("plant.mjcf", f"MuJoCo cannot load {str(mjcf)!r}: {exc}") from None
        if order not in (1, 2):
            raise SpecError("plant.order", f"must be 1 or 2, got {order!r}")
        if timestep is not None:
            if not (math.isfinite(timestep) and timestep > 0):
                raise SpecError("plant.timestep", f"must be a positive number of seconds, "
                                                  f"got {timestep!r}")
            self.model.opt.timestep = float(timestep)
        self.timestep = float(self.model.opt.timestep)
        self.data = mujoco.MjData(self.model)
        self.order = order
        self._qpos, self._qvel = [], []
        for name in joints:
            jid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, name)
            if jid < 0:
                raise SpecError("plant.joints", f"the model has no joint {name!r}")
            if int(self.model.jnt_type[jid]) not in (int(mujoco.mjtJoint.mjJNT_SLIDE),
                                                     int(mujoco.mjtJoint.mjJNT_HINGE)):
                raise SpecError("plant.joints", f"joint {name!r} is not a slide or hinge "
                                                "joint (one position each)")
            self._qpos.append(int(self.model.jnt_qposadr[jid]))
            self._qvel.append(int(self.model.jnt_dofadr[jid]))
        self._ctrl = []
        for name in actuators:
            aid = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
            if aid < 0:
                raise SpecError("plant.actuators", f"the model has no actuator {name!r}")
            self._ctrl.append(aid)
        self.nstates = order * len(self._qpos)
        self.ninputs = len(self._ctrl)
        self.contact_count = 0
        self.first_contact = None
        #: geoms that are ground planes (their contacts are not collisions)
        self._plane = np.asarray(self.model.geom_type) == int(mujoco.mjtGeom.mjGEOM_PLANE)

    def state(self) -> np.ndarray:
        """The spec's state read from the model, shape (nstates,)."""
        # the state layout's blocks: the positions, then (order 2) the velocities
        blocks = (self.data.qpos[self._qpos], self.data.qvel[self._qvel])[:self.order]
        return np.concatenate(blocks).astype(float)

    def reset(self, x0) -> np.ndarray:
        """Reset the model (``mj_resetData``) and set the spec's initial state.

        Parameters
        ----------
        x0 : array_like, shape (nstates,)
            Positions (and, for order 2, velocities) of the joints.

        Returns
        -------
        ndarray, shape (nstates,)
            The state read back after ``mj_forward``.
        """
        mj = self._mj
        mj.mj_resetData(self.model, self.data)
        x0 = np.asarray(x0, dtype=float)
        n = len(self._qpos)
        # block k of the state layout: the positions, then (order 2) the velocities
        blocks = list(zip((self.data.qpos, self.data.qvel), (self._qpos, self._qvel)))
        for k, (values, index) in enumerate(blocks[:self.order]):
            values[index] = x0[k * n:(k + 1) * n]
        mj.mj_forward(self.model, self.data)
        self.contact_count, self.first_contact = 0, None
        return self.state()

    def steps_per_period(self, dt: float) -> int:
        """Whole timesteps in a sampling period.

        Parameters
        ----------
        dt : float
            The sampling period, s.

        Returns
        -------
        int
            ``dt / timestep``.

        Raises
        ------
        SpecError
            Field ``controller.rate_hz``: the period is not a whole number of timesteps.
        """
        steps = self._whole_steps(dt)
        if steps is None or steps < 1:
            raise SpecError("controller.rate_hz",
                            f"the sampling period {dt:g} s is not a whole number of the "
                            f"MuJoCo model's timesteps ({self.timestep:g} s)")
        return steps

    def check_delay(self, delay: float, dt: float) -> None:
        """That a computation delay splits each sampling period into whole timesteps.

        Parameters
        ----------
        delay : float
            ``[controller] delay``, s: the previous command is held on ``[t_k, t_k +
            delay)``, the new one from ``t_k + delay``.
        dt : float
            The sampling period, s.

        Raises
        ------
        SpecError
            Field ``controller.rate_hz``: the period is not a whole number of timesteps;
            field ``controller.delay``: the delay is not.
        """
        self.steps_per_period(dt)
        if self._whole_steps(delay) is None:
            raise SpecError("controller.delay",
                            f"the computation delay {delay:g} s must be a whole number of "
                            f"MuJoCo timesteps ({self.timestep:g} s) to be simulated on "
                            "MuJoCo")

    def _whole_steps(self, duration: float) -> int | None:
        """``duration`` in timesteps where it is a whole number of them (to 1e-9 relative),
        else ``None``."""
        ratio = duration / self.timestep
        steps = int(round(ratio))
        return steps if abs(ratio - steps) <= 1e-9 * max(1.0, ratio) else None

    def _name(self, geom: int) -> str:
        name = self._mj.mj_id2name(self.model, self._mj.mjtObj.mjOBJ_GEOM, geom)
        return name if name else f"geom {geom}"

    def advance(self, t: float, u, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Hold ``u`` for ``dt`` seconds of ``mj_step``.

        Parameters
        ----------
        t : float
            Time at the start, s (for the contact record).
        u : array_like, shape (ninputs,)
            The held input, written to the actuators' ``ctrl``.
        dt : float
            The sampling period, s, or with a computation delay a part of it: a whole
            number of timesteps (none for a part of length zero).

        Returns
        -------
        states : ndarray, shape (m, nstates)
            The state after each of the ``m`` timesteps.
        times : ndarray, shape (m,)
            Their times, s.

        Raises
        ------
        SpecError
            Field ``controller.rate_hz``: ``dt`` is not a whole number of timesteps.
        """
        mj = self._mj
        steps = 0 if self._whole_steps(dt) == 0 else self.steps_per_period(dt)
        self.data.ctrl[self._ctrl] = np.asarray(u, dtype=float)
        states = np.empty((steps, self.nstates))
        for m in range(steps):
            mj.mj_step(self.model, self.data)
            if self.data.ncon:
                g1, g2 = self.data.contact.geom1, self.data.contact.geom2
                touching = ~(self._plane[g1] | self._plane[g2])
                if touching.any():
                    self.contact_count += 1
                    if self.first_contact is None:
                        k = int(np.argmax(touching))
                        self.first_contact = (t + (m + 1) * self.timestep,
                                              self._name(int(g1[k])), self._name(int(g2[k])))
            states[m] = self.state()
        return states, t + self.timestep * np.arange(1, steps + 1)


class DriveMujocoPlant(MujocoPlant):
    """A differential-drive base on MuJoCo: ``(v, omega)`` turned into wheel speeds.

    The state is the base's ``(x, y, theta)``, read from three joints of the chassis (two
    slides and the yaw hinge); the input ``u = (v, omega)`` goes to the two wheels' velocity
    actuators as the speeds exact wheels of the nominal radius would need
    (:meth:`~stt_codegen.spec.differential_drive.DifferentialDrive.wheel_speeds`): the
    base's driver, as on the robot. The MJCF's own wheels, masses and contacts are the
    plant.

    Parameters
    ----------
    mjcf : str or pathlib.Path
        The model file.
    joints : sequence of str, length 3
        The joints of ``x``, ``y`` and ``theta``.
    actuators : sequence of str, length 2
        The right and the left wheel's velocity actuators.
    drive : DifferentialDrive
        Its ``wheel_radius`` and ``track_width`` turn ``(v, omega)`` into wheel speeds.
    timestep : float, optional
        Overrides the model's timestep, s.

    Raises
    ------
    SpecError
        As :class:`MujocoPlant`.
    """

    def __init__(self, mjcf: str | Path, joints, actuators, drive,
                 timestep: float | None = None) -> None:
        super().__init__(mjcf, joints, actuators, 1, timestep)
        self.drive = drive

    def advance(self, t: float, u, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Hold the wheel speeds of ``u = (v, omega)`` for ``dt`` seconds of ``mj_step``.

        Parameters
        ----------
        t : float
            Time at the start, s.
        u : array_like, shape (2,)
            ``v`` (m/s) and ``omega`` (rad/s).
        dt : float
            The sampling period, s, or a part of it (as :meth:`MujocoPlant.advance`).

        Returns
        -------
        states : ndarray, shape (m, 3)
        times : ndarray, shape (m,)
        """
        return super().advance(t, self.drive.wheel_speeds(u), dt)
