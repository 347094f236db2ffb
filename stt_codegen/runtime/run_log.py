"""A closed-loop run as ROS 2 messages in an MCAP file, for Foxglove or ``ros2 bag play``.

Written with ``mcap`` and ``mcap-ros2-support`` (the optional extra ``ros``), which encode
ROS 2 messages (CDR) without a ROS runtime; the message definitions are the ROS 2 Humble
ones (Jazzy's are the same for these types), stored in the file. One message a sampling
instant ``t_k`` on each of the topics of :data:`TOPICS` but ``/stt/path`` (one message, at
the last instant), stamped ``t_k`` (from 0) in the frame ``map``. A state space of fewer
than three dimensions is drawn in the plane ``z = 0``; of more, in its first three.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import SpecError
from ..system import atomic_write
from ..tube import reference

if TYPE_CHECKING:
    from ..design.result import Design
    from .simulate import SimulationResult

__all__ = ["FRAME", "TOPICS", "check_log_path", "write_run_log"]

#: Each topic written and its ROS 2 message type.
TOPICS = {
    "/stt/state": "geometry_msgs/msg/PoseStamped",
    "/stt/command": "std_msgs/msg/Float64MultiArray",
    "/stt/markers": "visualization_msgs/msg/MarkerArray",
    "/stt/path": "nav_msgs/msg/Path",
}
#: The frame every message is stamped in.
FRAME = "map"


# ROS 2 message definitions (Humble), the text a .msg file holds.
_DEFINITIONS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec",
    "builtin_interfaces/Duration": "int32 sec\nuint32 nanosec",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "std_msgs/ColorRGBA": "float32 r\nfloat32 g\nfloat32 b\nfloat32 a",
    "std_msgs/MultiArrayDimension": "string label\nuint32 size\nuint32 stride",
    "std_msgs/MultiArrayLayout": "std_msgs/MultiArrayDimension[] dim\nuint32 data_offset",
    "std_msgs/Float64MultiArray": "std_msgs/MultiArrayLayout layout\nfloat64[] data",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Quaternion": "float64 x\nfloat64 y\nfloat64 z\nfloat64 w",
    "geometry_msgs/Pose": "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation",
    "geometry_msgs/PoseStamped": "std_msgs/Header header\ngeometry_msgs/Pose pose",
    "nav_msgs/Path": "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses",
    "sensor_msgs/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data",
    "visualization_msgs/UVCoordinate": "float32 u\nfloat32 v",
    "visualization_msgs/MeshFile": "string filename\nuint8[] data",
    "visualization_msgs/Marker": "\n".join([
        "int32 ARROW=0", "int32 CUBE=1", "int32 SPHERE=2", "int32 CYLINDER=3",
        "int32 LINE_STRIP=4", "int32 LINE_LIST=5", "int32 CUBE_LIST=6", "int32 SPHERE_LIST=7",
        "int32 POINTS=8", "int32 TEXT_VIEW_FACING=9", "int32 MESH_RESOURCE=10",
        "int32 TRIANGLE_LIST=11", "int32 ADD=0", "int32 MODIFY=0", "int32 DELETE=2",
        "int32 DELETEALL=3", "std_msgs/Header header", "string ns", "int32 id", "int32 type",
        "int32 action", "geometry_msgs/Pose pose", "geometry_msgs/Vector3 scale",
        "std_msgs/ColorRGBA color", "builtin_interfaces/Duration lifetime",
        "bool frame_locked", "geometry_msgs/Point[] points", "std_msgs/ColorRGBA[] colors",
        "string texture_resource", "sensor_msgs/CompressedImage texture",
        "visualization_msgs/UVCoordinate[] uv_coordinates", "string text",
        "string mesh_resource", "visualization_msgs/MeshFile mesh_file",
        "bool mesh_use_embedded_materials"]),
    "visualization_msgs/MarkerArray": "visualization_msgs/Marker[] markers",
}
_CUBE, _SPHERE, _CYLINDER = 1, 2, 3
#: Colours (r, g, b, a) of the markers: the tube, an obstacle, the target, an obstacle
#: sensed at run time.
_COLOURS = {"tube": (1.0, 0.55, 0.0, 0.35), "obstacle": (0.45, 0.45, 0.45, 0.8),
            "target": (0.0, 0.7, 0.2, 0.35), "sensed": (0.55, 0.3, 0.75, 0.6)}
#: Thickness of a box drawn in the plane (a state space of fewer than 3 dimensions).
_FLAT = 0.01


def _message_definition(name: str) -> str:
    """The schema text of ``name``: its definition, then each type it uses (depth first,
    once) after a line of ``=`` and ``MSG: <type>``, as ROS 2 writes it in a bag."""
    order: list[str] = []

    def visit(type_name: str) -> None:
        for line in _DEFINITIONS[type_name].splitlines():
            field_type = line.split()[0].split("[")[0]
            if "/" in field_type and field_type not in order and "=" not in line:
                order.append(field_type)
                visit(field_type)
    visit(name)
    return _DEFINITIONS[name] + "".join(f"\n{'=' * 80}\nMSG: {dep}\n{_DEFINITIONS[dep]}"
                                        for dep in order)


def _stamp(t: float) -> dict[str, Any]:
    sec = int(np.floor(t))
    return {"stamp": {"sec": sec, "nanosec": int(round((t - sec) * 1e9)) % 1_000_000_000},
            "frame_id": FRAME}


def _xyz(values) -> dict[str, float]:
    v = [float(a) for a in values[:3]] + [0.0] * (3 - min(3, len(values)))
    return {"x": v[0], "y": v[1], "z": v[2]}


def _pose(t: float, point) -> dict[str, Any]:
    return {"header": _stamp(t), "pose": {"position": _xyz(point), "orientation": {
        "x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}}}


def _box_marker(t: float, ns: str, ident: int, lower, upper, colour: str,
                shape: int = _CUBE) -> dict[str, Any]:
    """A marker filling the box ``[lower, upper]`` (a ``shape`` of its size: a cube, or an
    upright cylinder in it)."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    scale = _xyz(upper - lower)
    if len(lower) < 3:
        scale["z"] = _FLAT
    r, g, b, a = _COLOURS[colour]
    return {"header": _stamp(t), "ns": ns, "id": ident, "type": shape, "action": 0,
            "pose": {"position": _xyz((lower + upper) / 2), "orientation": {
                "x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}},
            "scale": scale, "color": {"r": r, "g": g, "b": b, "a": a},
            "lifetime": {"sec": 0, "nanosec": 0}, "frame_locked": False, "points": [],
            "colors": [], "texture_resource": "", "texture": {
                "header": _stamp(t), "format": "", "data": b""},
            "uv_coordinates": [], "text": "", "mesh_resource": "",
            "mesh_file": {"filename": "", "data": b""}, "mesh_use_embedded_materials": False}


def _sensed_boxes(spec, trajectory) -> list[tuple[np.ndarray, np.ndarray]] | None:
    """Per sample, the lower and upper corners (J, n) of each sensed obstacle's box: its
    disc on the sensing dimensions, the state space on the others; ``None`` for a run
    without sensed obstacles."""
    if trajectory.sensed_positions is None or spec.sensing is None:
        return None
    dims = list(spec.sensing.dims)
    radii = np.asarray(trajectory.sensed_radii, dtype=float)[:, None]
    out = []
    for centres in trajectory.sensed_positions:
        lower = np.tile(np.asarray(spec.state_space.lower, dtype=float), (len(radii), 1))
        upper = np.tile(np.asarray(spec.state_space.upper, dtype=float), (len(radii), 1))
        lower[:, dims], upper[:, dims] = centres - radii, centres + radii
        out.append((lower, upper))
    return out


def check_log_path(path: str | Path) -> None:
    """Refuse a log path before any work: not ``.mcap``, a missing folder, or
    ``mcap-ros2-support`` not installed.

    Parameters
    ----------
    path : str or pathlib.Path
        Where the run will be written.

    Raises
    ------
    SpecError
        Field ``log``, naming what is wrong (the package and the install command when
        it is missing).
    """
    path = Path(path)
    if path.suffix.lower() != ".mcap":
        raise SpecError("log", f"must end in .mcap, got {str(path)!r}")
    if not (path.parent if str(path.parent) else Path(".")).is_dir():
        raise SpecError("log", f"folder {str(path.parent)!r} does not exist")
    try:
        import mcap_ros2.writer  # noqa: F401
    except ImportError:
        raise SpecError("log", "mcap-ros2-support is not installed: install the optional "
                               'extra with pip install ".[ros]"') from None


def write_run_log(design: Design, result: SimulationResult, path: str | Path) -> Path:
    """Write a run as ROS 2 messages in an MCAP file (``stt-codegen simulate --log``).

    Topics (:data:`TOPICS`), one message a sampling instant ``t_k`` (``N`` instants) on
    each but the path: ``/stt/state`` the point the tube holds (``PoseStamped``, its first
    three coordinates, orientation the identity); ``/stt/command`` the input ``u_k``
    (``Float64MultiArray``, input units); ``/stt/markers`` the tube ``[gamma_L,
    gamma_U]`` of eq. (10) at the run's ``alpha`` (namespace ``tube``; in a run with sensed
    obstacles, :func:`~.sensed.simulate_sensed`, the tube active at ``t_k``), the static
    obstacles' boxes (``obstacles``) and the target (``target``) as ``CUBE`` markers, and
    in a run with sensed obstacles each of them where it is at ``t_k`` (``sensed``, id its
    index, seen or not), a ``CYLINDER`` of its diameter on the ``[sensing] dims`` across
    the state space on the other axes (a ``SPHERE`` when it is sensed on the three axes
    drawn) (``MarkerArray``); ``/stt/path`` the whole trajectory
    (``Path``, one message at the last instant). Stamped ``t_k`` s from 0 in the frame
    ``map``; written atomically.

    Parameters
    ----------
    design : Design
        The design the run used.
    result : SimulationResult
        A run with its ``trajectory`` (``t`` (N,), ``x`` (N, n), ``u`` (N, m), ``alpha``
        (N, 2n)).
    path : str or pathlib.Path
        The MCAP file; its folder must exist.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    SpecError
        As :func:`check_log_path`, or the run has no trajectory (field ``log``).
    """
    check_log_path(path)
    from mcap_ros2.writer import Writer
    trajectory = result.trajectory
    if trajectory is None:
        raise SpecError("log", "the run has no trajectory to write")
    spec = design.spec
    if trajectory.gamma_L is not None:          # the tube active at each sample
        g_l, g_u = trajectory.gamma_L, trajectory.gamma_U
    else:
        g_l, g_u, _, _ = reference.adaptive_tube(design.tube, trajectory.t,
                                                 trajectory.alpha)
    boxes = spec.obstacle_boxes()
    target = spec.target_set
    sensed = _sensed_boxes(spec, trajectory)
    # a ball sensed on the three axes drawn is a sphere; on fewer, an upright cylinder
    ball = (_SPHERE if spec.sensing is not None and {0, 1, 2} <= set(spec.sensing.dims)
            else _CYLINDER)

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as stream:
            writer = Writer(stream)
            # the schema names as ROS 2 bags store them, pkg/msg/Type
            schemas = {topic: writer.register_msgdef(
                kind, _message_definition(kind.replace("/msg/", "/")))
                for topic, kind in TOPICS.items()}
            m = trajectory.u.shape[1]
            for k, t in enumerate(trajectory.t):
                t = float(t)
                stamp = int(round(t * 1e9))
                writer.write_message("/stt/state", schemas["/stt/state"],
                                     _pose(t, trajectory.x[k]), log_time=stamp,
                                     publish_time=stamp, sequence=k)
                writer.write_message("/stt/command", schemas["/stt/command"], {
                    "layout": {"dim": [{"label": "u", "size": m, "stride": m}],
                               "data_offset": 0},
                    "data": [float(v) for v in trajectory.u[k]]},
                    log_time=stamp, publish_time=stamp, sequence=k)
                markers = [_box_marker(t, "tube", 0, g_l[k], g_u[k], "tube")]
                markers += [_box_marker(t, "obstacles", b, box.lower, box.upper, "obstacle")
                            for b, box in enumerate(boxes)]
                markers.append(_box_marker(t, "target", 0, target.lower, target.upper,
                                           "target"))
                markers += [_box_marker(t, "sensed", j, lo, hi, "sensed", ball)
                            for j, (lo, hi) in enumerate(zip(*sensed[k]))] if sensed else []
                writer.write_message("/stt/markers", schemas["/stt/markers"],
                                     {"markers": markers}, log_time=stamp,
                                     publish_time=stamp, sequence=k)
            end = float(trajectory.t[-1])
            stamp = int(round(end * 1e9))
            writer.write_message("/stt/path", schemas["/stt/path"], {
                "header": _stamp(end),
                "poses": [_pose(float(t), x) for t, x in zip(trajectory.t, trajectory.x)]},
                log_time=stamp, publish_time=stamp, sequence=0)
            writer.finish()

    atomic_write(Path(path), write, field="log")
    return Path(path)
