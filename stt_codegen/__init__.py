"""stt-codegen: spatiotemporal-tube controllers for prescribed-time reach-avoid-stay tasks.

The method is "Prescribed-time Reach-Avoid-Stay Specifications for Unknown Systems: A
Spatiotemporal Tubes Approach". The front door, in the order of the flow (see
``docs/library.md`` and ``docs/architecture.md``):

* :func:`load_spec` - read and validate a spec (a bundled case name or a TOML file);
  :meth:`Spec.from_dict` - the same from a dictionary;
* :func:`design_tube` - choose windows (5), circumvents (6)-(9) and the gain of law (13),
  and certify the tube (10) for every ``t``; returns a :class:`Design`, which carries
  its spec (``design.spec``) and its tube (``design.tube``, a :class:`TubeDesign`);
* :func:`load_fleet`, :func:`design_fleet` - several robots sharing a state space
  (:class:`FleetSpec`): each robot's tube designed to keep clear of the others' at every
  ``t``, every pair certified (:class:`FleetDesign`, docs/fleets.md);
  :func:`generate_fleet`, :func:`simulate_fleet` - a controller folder per robot, and
  every robot's closed loop with every pair's closest approach; :func:`verify_fleet` -
  every robot verified and every pair certified again (:class:`FleetVerification`);
  :func:`plot_fleet` - the fleet in time slices;
* :func:`generate` - write the standalone C and Python controllers of a design into a
  folder;
* :func:`simulate` - run a design's sampled controller in closed loop and judge
  Definition 2.1;
* :func:`verify` - the paper's lemmas, the assumptions and the tube certificate of a
  design (or of a spec, designed first), as a :class:`VerificationReport`
  (:func:`stt_codegen.verification.command.verify`);
* :func:`plot_design`, :func:`plot_run` - figures of a design, and of a run;
* :func:`controller_system`, :func:`sampled_plant` - the sampled controller and the plant
  over a period as discrete-time python-control systems (``ct.interconnect``);
* :func:`start_plan`, :func:`replan` - a tube replanned at run time around obstacles a
  sensor reports (:class:`SensedObstacle`) within the spec's ``[sensing]`` envelope;
  :func:`simulate_sensed` - the closed loop among obstacles the design does not know
  (:class:`WalkingObstacle`, or a file of them: :func:`load_walking_obstacles`),
  docs/sensing.md;
* :class:`Progress` - what ``design_tube`` and ``verify`` pass to a ``progress`` callback;
* :func:`import_pointmaze` - the spec of a maze of gymnasium-robotics' PointMaze (the
  ``mujoco`` extra);
* the errors, in three kinds: :class:`SpecError` (bad input), :class:`DesignError` (no
  design, a negative outcome), :class:`ToolchainError` (a tool or an internal step
  failed); all are :class:`SttError`.

``generate``, ``simulate``, ``verify`` and the plots take the :class:`Design` itself, so a
tube is never paired with another spec; given anything else (a ``TubeDesign``, a ``Spec``
where a design is needed) they raise ``TypeError`` saying to call :func:`design_tube`::

    import stt_codegen as stt
    design = stt.design_tube(stt.load_spec("omnirobot-s1"))
    stt.generate(design, "out", languages=["c"], precision="single")
    result = stt.simulate(design, backend="c")
    stt.plot_run(design, result, "run.png")
    assert stt.verify(design).passed

``import stt_codegen`` is cheap: each name is imported on first use (PEP 562), so the
command line and a notebook pay only for what they call.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from .errors import DesignError, SpecError, SttError, ToolchainError, UnitWarning
from .version import __version__

#: Public name -> module that defines it; imported on first attribute access.
_LAZY: dict[str, str] = {
    "Spec": "stt_codegen.spec.loader",
    "load_spec": "stt_codegen.spec.loader",
    "bundled_cases": "stt_codegen.cases",
    "bundled_fleets": "stt_codegen.cases",
    "FleetSpec": "stt_codegen.spec.fleet",
    "load_fleet": "stt_codegen.spec.fleet",
    "design_fleet": "stt_codegen.design.fleet",
    "FleetDesign": "stt_codegen.design.fleet",
    "generate_fleet": "stt_codegen.codegen.fleet",
    "simulate_fleet": "stt_codegen.runtime.fleet",
    "verify_fleet": "stt_codegen.verification.fleet",
    "plot_fleet": "stt_codegen.runtime.fleet_plots",
    "FleetVerification": "stt_codegen.verification.fleet",
    "TubeDesign": "stt_codegen.tube.parameters",
    "design_tube": "stt_codegen.design.search",
    "Design": "stt_codegen.design.result",
    "generate": "stt_codegen.codegen.api",
    "simulate": "stt_codegen.runtime.simulate",
    "SimulationResult": "stt_codegen.runtime.simulate",
    "plot_design": "stt_codegen.runtime.plots",
    "plot_run": "stt_codegen.runtime.plots",
    "VerificationReport": "stt_codegen.proofs.check",
    "verify": "stt_codegen.verification.command",
    "import_pointmaze": "stt_codegen.pointmaze",
    "SensedObstacle": "stt_codegen.spec.sensing",
    "SensedPlan": "stt_codegen.design.sensed",
    "ReplanFailure": "stt_codegen.design.sensed",
    "start_plan": "stt_codegen.design.sensed",
    "replan": "stt_codegen.design.sensed",
    "simulate_sensed": "stt_codegen.runtime.sensed",
    "WalkingObstacle": "stt_codegen.runtime.sensed",
    "load_walking_obstacles": "stt_codegen.runtime.walking_file",
    "Progress": "stt_codegen.progress",
    "controller_system": "stt_codegen.runtime.iosystem",
    "sampled_plant": "stt_codegen.runtime.iosystem",
}

__all__ = ["DesignError", "SpecError", "SttError", "ToolchainError", "UnitWarning",
           "__version__", *sorted(_LAZY)]

if TYPE_CHECKING:  # for type checkers and IDEs; at run time, __getattr__ below
    from .codegen.api import generate
    from .design.result import Design
    from .design.search import design_tube
    from .runtime.iosystem import controller_system, sampled_plant
    from .runtime.plots import plot_design, plot_run
    from .runtime.simulate import SimulationResult, simulate
    from .cases import bundled_cases, bundled_fleets
    from .codegen.fleet import generate_fleet
    from .design.fleet import FleetDesign, design_fleet
    from .runtime.fleet import simulate_fleet
    from .verification.fleet import FleetVerification, verify_fleet
    from .runtime.fleet_plots import plot_fleet
    from .spec.fleet import FleetSpec, load_fleet
    from .pointmaze import import_pointmaze
    from .spec.sensing import SensedObstacle
    from .design.sensed import ReplanFailure, SensedPlan, replan, start_plan
    from .runtime.sensed import WalkingObstacle, simulate_sensed
    from .runtime.walking_file import load_walking_obstacles
    from .spec.loader import Spec, load_spec
    from .tube.parameters import TubeDesign
    from .proofs.check import VerificationReport
    from .progress import Progress
    from .verification.command import verify


def __getattr__(name: str) -> Any:
    """Import a public name on first use (PEP 562)."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'stt_codegen' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
