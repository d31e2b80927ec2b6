"""A model's regressors as functions of what a run records: the device's actuated joints alone.

A run on a device records its actuated joints (a parallel device's actuators' angles, and a hybrid device's wrist
joints), while a parallel model's regressors take the platform's pose as well, tau = Y(q, p, qd, qdd) pi (the
consistent pair of :mod:`symkin.parallel.regressor`).  :class:`DeviceRegressors` asks the run-time mechanism
(:class:`symkin.mechanism.actuated.Mechanism`) for each sample's assembly and the regressors bound to the device's
joints: the closed-form fk (the same assembly the model's home pose is in); for a platform without one (the
Stewart-Gough platform) Newton's method on the generated leg equations from the home pose, a sample that does not
converge from there continued from the previous sample's pose (the run is continuous); for legs without the
distance form each sample's passive joints and pose continued from the home assembly along the run, and the
generated ``closure_regressor`` and ``closure_base_regressor`` taken to the actuators there
(:func:`symkin.runtime.closure_dynamics.closure_regressor`: Y = W^T Y_z).  A sample where the legs do not assemble
is refused with its CSV row.  An open chain's regressors take its joints as they are.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symkin.identification.estimation import DataError
from symkin.analysis.needs import DERIVED
from symkin.mechanism.actuated import Mechanism


class DeviceRegressors:
    """The regressors of a loaded model taking (q, qd, qdd) of the device's joints (``regressor``,
    ``base_regressor``, ``energy_regressor``); ``info`` is the mechanism's view (the device's joints as its
    coordinates, the regressors' records under their names), every other attribute the model's.

    Args:
        model: the loaded model.
        source: the run's file, named in the refusal of a sample that does not assemble.
    """

    def __init__(self, model: Any, source: str):
        self.model, self.source = model, source
        self.mechanism = Mechanism(model)
        self.info = self.mechanism.info

    def __getattr__(self, name: str) -> Any:
        return getattr(self.model, name)

    def pose(self, q: np.ndarray) -> np.ndarray:
        """The platform pose of every sample (N, task) (an open chain's: (N, 0)).

        Raises:
            DataError: naming the first sample (its CSV row) whose legs do not assemble.
        """
        if not self.mechanism.has_pose:
            return np.zeros(np.shape(q)[:-1] + (0,))
        p = self.mechanism.pose(q)
        bad = ~np.all(np.isfinite(p), axis=-1)
        if np.any(bad):
            row = int(np.argmax(bad))
            raise DataError(f"{self.source}: sample {row + 1} (row {row + 2}): the legs do not assemble at q = "
                            f"{np.array2string(np.asarray(q)[row], precision=6)} ({self.mechanism.unassembled}); "
                            "check the angles' zero and sign against the model's")
        return p

    def regressor(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> Any:
        self.pose(q)
        return self.mechanism.function("regressor")(q, qd, qdd)

    def base_regressor(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> Any:
        self.pose(q)
        return self.mechanism.function("base_regressor")(q, qd, qdd)

    def energy_regressor(self, q: np.ndarray, qd: np.ndarray) -> Any:
        self.pose(q)
        return self.mechanism.function("energy_regressor")(q, qd)


def run_regressors(model: Any, source: str, where: str) -> DeviceRegressors:
    """The regressors of a run in ``source`` (:class:`DeviceRegressors`) of a generated directory that holds what
    they need (``where`` names it in the refusal): the base regressor; where the device's joints carry a pose, fk
    (or the leg equations constraints and constraint_jacobians, for Newton's method); legs without the distance
    form, what ``DERIVED["identify"]`` derives them with.

    Raises:
        ValueError: naming what is missing and the ``symkin derive --only`` that gives it.
    """
    functions = model.info.functions
    needed = DERIVED["identify"].required_of(functions)
    if needed != DERIVED["identify"].outputs:  # legs without the distance form: the closure's functions
        missing = [f for f in needed if f not in functions]
        if missing:
            raise ValueError(f"{where}: the identification of legs without the distance form needs "
                             f"{', '.join(missing)}; derive them (symkin derive --only {','.join(needed)}, "
                             "and closure_energy_regressor for --method energy) or give the model file")
        return DeviceRegressors(model, source)
    regressors = DeviceRegressors(model, source)
    missing = [f for f in ("base_regressor",) if f not in functions]
    if not regressors.mechanism.has_pose:
        if missing:
            raise ValueError(f"{where}: the identification needs base_regressor; derive it (symkin derive --only "
                             "base_regressor,regressor) or give the model file")
        return regressors
    if "fk" not in functions and not {"constraints", "constraint_jacobians"} <= set(functions):
        missing.append("fk (or constraints and constraint_jacobians, for Newton's method)")
    if missing:
        raise ValueError(f"{where}: a parallel model's identification needs {' and '.join(missing)}; derive "
                         "them (symkin derive --only base_regressor,regressor,fk, or without a closed-form fk "
                         "--only base_regressor,regressor,constraints,constraint_jacobians) or give the model file")
    return regressors
