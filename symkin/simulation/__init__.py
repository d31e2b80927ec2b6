"""Simulation on the generated code (seed sec. 5, Figs. 8.17, 8.18, 8.21, 8.22).

The mechanism's forward and inverse dynamics come from the functions ``symkin derive``
emitted (any backend); nothing here derives symbolically.

* :class:`Plant` - joint-space dynamics (seed eq. 8.34) and the TCP point;
* :class:`ArmSystem` - the state, optionally with a mass-spring-damper user, and the
  power balance k + u - w;
* :func:`run_sampled` (RK4 under a zero-order-hold controller, the 1 kHz loop) and
  :func:`run_adaptive` (DOP853 to a tolerance, with located mode switches);
* :class:`JointStops` - mechanical stops at the joint limits (linear spring-dampers), their
  :class:`ContactModes` for event location, :mod:`symkin.simulation.contacts` the report;
* controllers :class:`ComputedTorque` and :class:`WallRenderer`, references
  :class:`JointSine` and :func:`task_circle`;
* :mod:`symkin.simulation.scenarios` - the scenarios of ``symkin simulate``.

Example::

    import numpy as np, symkin
    from symkin.simulation import ArmSystem, ComputedTorque, JointSine, Plant, run_sampled

    plant = Plant(symkin.load("generated/planar_2r"))
    system = ArmSystem(plant)
    reference = JointSine(np.radians([45, 45]), joint=1, amplitude=np.radians(30), frequency=1.0)
    q0, qd0, _ = reference(0.0)
    run = run_sampled(system.derivative, ComputedTorque(system, reference), system.initial(q0, qd0),
                      period=1e-3, steps=2000)
"""

from symkin.simulation.control import ComputedTorque, Wall, WallRenderer
from symkin.simulation.integrate import Run, SimulationError, rk4_step, run_adaptive, run_sampled
from symkin.simulation.plant import Plant
from symkin.simulation.stops import ContactModes, JointStops
from symkin.simulation.system import ArmSystem
from symkin.simulation.trajectory import JointSine, SplineReference, task_circle
from symkin.simulation.user import MassSpringDamperUser, sine_intent

__all__ = ["ArmSystem", "ComputedTorque", "ContactModes", "JointSine", "JointStops", "MassSpringDamperUser", "Plant",
           "Run", "SimulationError", "SplineReference", "Wall", "WallRenderer", "rk4_step", "run_adaptive",
           "run_sampled", "sine_intent", "task_circle"]
