"""A parallel model's regressors as functions of what a run records: the device's joints alone.

A run on a parallel device records its actuators' angles (and a hybrid device's wrist joints), while the
parallel regressors take the platform's pose as well, tau = Y(q, p, qd, qdd) pi (the consistent pair of
:mod:`symkin.parallel.regressor`).  Each sample's pose is the forward kinematics of its actuators, p = fk(q):
the generated closed form (the same assembly the model's home pose is in), or for a platform without one (the
Stewart-Gough platform) Newton's method on the generated leg equations (:func:`symkin.runtime.parallel.solve_fk`)
from the home pose, a sample that does not converge from there continued from the previous sample's pose (the
run is continuous); a sample where the legs do not assemble is refused with its row.  The device's coordinates
are the legs' actuators, then a hybrid device's wrist joints, as the regressors' rows.

Legs without the distance form (:class:`ClosureDeviceRegressors`) have neither: each sample's passive joints and
pose (s, p) are continued from the home assembly along the run (:class:`symkin.mechanism.closure.
ClosureAssembly`), and the regressors are the generated ``closure_regressor`` and ``closure_base_regressor``
taken to the actuators there (:func:`symkin.runtime.closure_dynamics.closure_regressor`: Y = W^T Y_z).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from symkin import mechanism
from symkin.analysis.identification import DataError
from symkin.runtime.closure_dynamics import closure_energy_regressor, closure_regressor
from symkin.mechanism.closure import ClosureAssembly


class DeviceRegressors:
    """The regressors of a loaded parallel model taking (q, qd, qdd) of the device's coordinates; every other
    attribute is the model's, but ``info``, whose coordinates are the device's (legs, then wrist)."""

    def __init__(self, model: Any, source: str):
        self.model, self.source = model, source
        info = model.info
        self.legs = len(info.coordinates)
        self.info = dataclasses.replace(info, coordinates=info.device_coordinates, wrist=())
        self._last_pose: tuple[np.ndarray, np.ndarray] | None = None  # (q, fk(q)) of the last part of a run

    def __getattr__(self, name: str) -> Any:
        return getattr(self.model, name)

    def pose(self, q: np.ndarray) -> np.ndarray:
        """p = fk(q_legs) of every sample (N, task); of the same array as the last call, that call's (a part of a
        run goes through several regressors: its poses are computed once).

        Raises:
            DataError: naming the first sample (its CSV row) whose legs do not assemble.
        """
        if self._last_pose is not None and self._last_pose[0] is q:
            return self._last_pose[1]
        with np.errstate(invalid="ignore"):  # NaN where the legs do not assemble: refused below with the row
            if "fk" in self.model.info.functions:
                p = np.asarray(self.model.fk(q[..., :self.legs])[0], dtype=float)
            else:
                p = self._solved_poses(q[..., :self.legs])
        _refuse_unassembled(self.source, q[..., :self.legs], p, "fk has no solution")
        self._last_pose = (q, p)
        return p

    def _solved_poses(self, q: np.ndarray) -> np.ndarray:
        """p with f(q, p) = 0 for every sample (N, task) by Newton from the home pose; the samples that do not
        converge from there start again from the previous sample's pose, pass after pass while some do (NaN
        where none does)."""
        from symkin.runtime.parallel import solve_fk

        p = np.array(solve_fk(self.model, q).solution)
        while True:
            failed = np.flatnonzero(~np.all(np.isfinite(p), axis=-1))
            failed = failed[(failed > 0) & np.all(np.isfinite(p[failed - 1]), axis=-1)]
            if not failed.size:
                return p
            p[failed] = solve_fk(self.model, q[failed], p[failed - 1]).solution
            if not np.any(np.all(np.isfinite(p[failed]), axis=-1)):
                return p

    def regressor(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> Any:
        return mechanism.of_device_joints(self.model, "regressor", self.pose)(q, qd, qdd)

    def base_regressor(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> Any:
        return mechanism.of_device_joints(self.model, "base_regressor", self.pose)(q, qd, qdd)

    def energy_regressor(self, q: np.ndarray, qd: np.ndarray) -> Any:
        return mechanism.of_device_joints(self.model, "energy_regressor", self.pose)(q, qd)


def _refuse_unassembled(source: str, q: np.ndarray, solved: np.ndarray, why: str) -> None:
    """Raises DataError naming the first sample (its CSV row) whose ``solved`` assembly is not finite."""
    bad = ~np.all(np.isfinite(solved), axis=-1)
    if np.any(bad):
        row = int(np.argmax(bad))
        raise DataError(f"{source}: sample {row + 1} (row {row + 2}): the legs do not assemble at q = "
                        f"{np.array2string(q[row], precision=6)} ({why}); check the angles' zero and sign against "
                        "the model's")


class ClosureDeviceRegressors:
    """The regressors of a loaded model of legs without the distance form taking (q, qd, qdd) of its actuators:
    ``regressor``, ``base_regressor`` and ``energy_regressor`` are the generated ``closure_regressor``,
    ``closure_base_regressor`` and ``closure_energy_regressor`` taken to the actuators at each sample's assembly
    (module docstring), and ``info`` names them so; every other attribute is the model's."""

    def __init__(self, model: Any, source: str):
        self.model, self.source = model, source
        functions = dict(model.info.functions)
        for name in ("regressor", "base_regressor", "energy_regressor"):
            if f"closure_{name}" in functions:
                functions[name] = functions[f"closure_{name}"]
        self.info = dataclasses.replace(model.info, functions=functions)
        self._assembly = ClosureAssembly(model)
        self._last: tuple[np.ndarray, tuple[np.ndarray, np.ndarray]] | None = None

    def __getattr__(self, name: str) -> Any:
        return getattr(self.model, name)

    def assembly(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(s, p) of every sample (N, ns), (N, m), continued along the run from the home assembly; of the same array
        as the last call, that call's.

        Raises:
            DataError: naming the first sample (its CSV row) where the legs stop closing.
        """
        if self._last is not None and self._last[0] is q:
            return self._last[1]
        s, p = self._assembly(q)
        _refuse_unassembled(self.source, q, np.concatenate([s, p], axis=-1),
                            "the closure has no solution continued from the previous sample")
        self._last = (q, (s, p))
        return s, p

    def regressor(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return closure_regressor(self.model, q, *self.assembly(q), qd, qdd)

    def base_regressor(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return closure_regressor(self.model, q, *self.assembly(q), qd, qdd, base=True)

    def energy_regressor(self, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return closure_energy_regressor(self.model, q, *self.assembly(q), qd)
