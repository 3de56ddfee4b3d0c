"""ccopt: manipulation of unknown objects through contact configuration regulation.

A flat, impedance-controlled hand presses an unknown convex polygon against the ground. From the wrist
wrench and the hand pose alone, ccopt *estimates* the generalized friction cone, the contact modes
and geometry and the kinematics ``(θ_o, s_h, s_g)`` (:class:`Estimator`), and *controls* the hand's
impedance target with a small, code-generated QP (:class:`Controller`) so that a commanded pivot,
hand slide or ground slide happens while every other contact keeps its mode. It re-implements Doshi,
Taylor & Rodriguez, "Manipulation of unknown objects via contact configuration regulation", on
simulated robots (MuJoCo, Pinocchio). The architecture is described in ``docs/architecture.md``.

A closed loop in five lines::

    import ccopt
    obj = ccopt.make_object("paper-triangle")
    done = ccopt.run_experiment(obj, ccopt.load_schedule("smoke"), seed=0)
    print(done.summary["theta_err_deg"], done.summary["unintended_slips"])

The names below are loaded on first use, so ``import ccopt`` stays light.
"""

from __future__ import annotations

import importlib
from importlib import metadata

try:
    __version__ = metadata.version("ccopt")
except metadata.PackageNotFoundError:  # running from a source tree that was never installed
    __version__ = "0+unknown"

_EXPORTS = {
    # objects and schedules
    "PlanarObject": "ccopt.objects",
    "make_object": "ccopt.objects",
    "from_vertices": "ccopt.objects",
    "OBJECT_NAMES": "ccopt.objects",
    "Schedule": "ccopt.schedule",
    "Step": "ccopt.schedule",
    "load_schedule": "ccopt.schedule",
    "Motion": "ccopt.modes",
    "ContactConfiguration": "ccopt.modes",
    # the robot and a run
    "Hand": "ccopt.hand",
    "LoopParams": "ccopt.closed_loop",
    "run": "ccopt.closed_loop",
    "run_experiment": "ccopt.experiment",
    "Experiment": "ccopt.experiment",
    "load_record": "ccopt.record",
    "summarize": "ccopt.metrics",
    # estimation and control
    "Estimator": "ccopt.estimation.estimator",
    "EstimatorParams": "ccopt.estimation.estimator",
    "Estimate": "ccopt.estimation.estimator",
    "Controller": "ccopt.control.controller",
    "ControllerParams": "ccopt.control.controller",
    "QPInstance": "ccopt.control.qp",
    "make_solver": "ccopt.control.qp",
    # the model
    "contact": "ccopt.contact",
    "geometry": "ccopt.geometry",
    "statics": "ccopt.statics",
    "plots": "ccopt.plots",
}
"""Public name → the module that defines it."""

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str) -> object:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'ccopt' has no attribute {name!r}")
    loaded = importlib.import_module(module)
    value = loaded if module.rsplit(".", 1)[-1] == name else getattr(loaded, name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
