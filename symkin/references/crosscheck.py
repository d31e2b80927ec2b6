"""symkin against an independent reference on the same robot: ``symkin crosscheck`` (Pinocchio; MuJoCo
as well for an MJCF file, :mod:`symkin.references.mujoco_reference`).

The reference reads the robot from a URDF and shares no code with symkin's derivation: a
URDF model file is given to Pinocchio as it is (with symkin's choice of chain: the joints
off it locked at the same values, :class:`~symkin.model.urdf_source.UrdfReduction`); a YAML
model goes through the URDF that ``symkin export`` writes (:mod:`symkin.model.urdf_export`);
a xacro or MJCF file goes through the URDF text symkin generates from it; ``reference_urdf``
replaces any of them by another file (e.g. the vendor's).  symkin's side is the
generated numpy code, derived into a temporary directory, so what is checked is what users run.

At ``samples`` random states within the joint limits (q; qd and qdd in [-1, 1]) it compares
every quantity both have: fk and the frame of every link (base_T_<link>), the geometric
Jacobian of the TCP and of every link frame (base_J_<link>) in base axes, M (CRBA), G, V (nonLinearEffects without gravity) and the
inverse dynamics tau (RNEA) of the chain, the locked joints at rest; joint springs (``springs:``, which a URDF
cannot hold) add the model's k (theta - theta_0) to the reference's G and tau (MuJoCo checks them
independently on an MJCF file).  Each row is the largest
normwise relative error ||symkin - reference||_F / ||reference||_F over the states (the
absolute error where the reference is zero).  Two exact methods differ by rounding only, so
the default tolerance is 1e-12; an edited file or a wrong convention shows as errors of
order 1e-3 to 1.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from symkin.errors import ModelError, Problem
from symkin.model.coordinates import coordinate_range, coupling_matrix

#: Largest normwise relative error accepted by default (two exact methods differ by rounding).
DEFAULT_TOLERANCE = 1e-12
KINEMATICS_OUTPUTS = ("fk", "frames", "jacobian_geometric", "frame_jacobians")
DYNAMICS_OUTPUTS = ("mass_matrix", "coriolis_vector", "gravity_vector", "inverse_dynamics")
#: The generated code checked by default: what users run in Python and in their control loops.
BACKENDS = ("numpy", "c")
#: Chains up to this many joints have C checked by default (its derivation grows as n^3: seconds at 7).
CORIOLIS_MATRIX_JOINTS = 7


@dataclass(frozen=True)
class Comparison:
    """One quantity: its largest error over the states, and a note (e.g. why it was skipped)."""

    quantity: str
    error: float
    note: str = ""


@dataclass(frozen=True)
class CrosscheckReport:
    """The comparisons of one model against the reference."""

    model: str
    reference: str
    samples: int
    tolerance: float
    comparisons: tuple[Comparison, ...]

    @property
    def failures(self) -> tuple[Comparison, ...]:
        return tuple(c for c in self.comparisons if not c.error <= self.tolerance)


def _pinocchio() -> Any:
    try:
        import pinocchio
    except ImportError:
        raise ModelError([Problem("<command line>", None, None, "--reference", "the reference 'pinocchio' is not "
                                  "installed", "pip install 'symkin[crosscheck]' (or pip install pin)")]) from None
    return pinocchio


def _normwise(got: np.ndarray, want: np.ndarray, terms: np.ndarray | None = None, natural: float = 0.0) -> float:
    """||got - want|| / max(||terms||, natural), where ``terms`` (default ``want``) bounds the magnitudes
    summed into ``want`` and ``natural`` is the quantity's natural size (:func:`_dynamics_references`).

    A quantity reduced to coordinates by a coupling, A^T v, can cancel to zero (a parallel-jaw
    finger's Coriolis torque): its rounding is relative to |A|^T |v|, not to the sum; one that
    vanishes (V at rest) is compared with the size its terms have elsewhere, not with rounding noise.
    """
    scale = max(float(np.linalg.norm(want if terms is None else terms)), natural)
    difference = float(np.linalg.norm(np.asarray(got, dtype=float) - want))
    return difference / scale if scale > 0 else difference


def _reduced(coupling: np.ndarray, value: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(A^T v, |A|^T |v|) of a joint vector, (A^T M A, |A|^T |M| |A|) of a joint matrix."""
    if value.ndim == 1:
        return coupling.T @ value, np.abs(coupling).T @ np.abs(value)
    return coupling.T @ value @ coupling, np.abs(coupling).T @ np.abs(value) @ np.abs(coupling)


def _sources(path: Path, reference_urdf: Path | None, urdf: Mapping[str, Any]) -> tuple[Any, str, Any, bool]:
    """(model, reference URDF text, reduction, whether the file is MJCF) for the model file ``path``."""
    from symkin.model import load_model
    from symkin.model.build import build_model
    from symkin.model.mjcf_source import read_mjcf_document
    from symkin.model.source_kind import MJCF, URDF, XACRO, source_kind
    from symkin.model.urdf_export import ROOT_LINK, TCP_LINK, export_urdf
    from symkin.model.urdf_source import UrdfReduction, read_urdf_document
    from symkin.model.xacro_source import read_xacro_document

    options = dict(urdf)
    allow_nonphysical = bool(options.pop("allow_nonphysical", False))
    kind = source_kind(path)
    if kind == URDF:
        document = read_urdf_document(path, **options)
        model = build_model(document, path.stem, allow_nonphysical)
        reduction = document.reduction
        text = reference_urdf.read_text() if reference_urdf else reduction.reference_text(path.read_text())
    elif kind in (XACRO, MJCF):  # the reference reads symkin's URDF text: the check is of its reading and derivation
        document, expanded = read_xacro_document(path, options.pop("xacro_args", None),
                                                 options.pop("xacro_packages", None), **options) if kind == XACRO \
            else read_mjcf_document(path, **options)
        model = build_model(document, path.stem, allow_nonphysical)
        reduction = document.reduction
        text = reference_urdf.read_text() if reference_urdf else reduction.reference_text(expanded)
    else:
        model = load_model(path, allow_nonphysical=allow_nonphysical)
        reduction = UrdfReduction(ROOT_LINK, TCP_LINK, {})
        text = reference_urdf.read_text() if reference_urdf else export_urdf(model)
    model.refuse_closed_loops("crosscheck compares serial chains with a URDF reference",
                              "cross-check a serial model (the parallel models' tests use their own closed-loop "
                              "references)")
    return model, text, reduction, kind == MJCF


def _link_frame(pin: Any, reference: Any, link: str) -> int:
    """The id of the reference's frame of URDF link ``link`` (a body frame: a joint may share its name)."""
    return reference.getFrameId(link, pin.FrameType.BODY)


def _coupling(model: Any) -> np.ndarray:
    """The coupling matrix A (joints x coordinates) at the default parameters; the identity without followers."""
    A = coupling_matrix(model)
    if A is None:
        return np.eye(len(model.joints))
    return np.array(A.xreplace(model.parameter_values), dtype=float)


def _states(model: Any, samples: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q within the joint ranges (:func:`~symkin.model.coordinates.coordinate_range`), qd and qdd in [-1, 1]."""
    rng = np.random.default_rng(seed)
    lower, upper = coordinate_range(model)
    n = model.dof
    return rng.uniform(lower, upper, (samples, n)), rng.uniform(-1, 1, (samples, n)), rng.uniform(-1, 1, (samples, n))


def crosscheck(path: str | Path, *, reference_urdf: str | Path | None = None, samples: int = 20, seed: int = 0,
               tolerance: float = DEFAULT_TOLERANCE, urdf: Mapping[str, Any] | None = None,
               backends: tuple[str, ...] = BACKENDS, coriolis_matrix: bool | None = None,
               progress: Callable[[str], None] | None = None) -> CrosscheckReport:
    """Compare the model in ``path`` (YAML or URDF) with Pinocchio (see the module docstring).

    Args:
        urdf: the keyword arguments of :func:`symkin.model.load_model` (for a URDF model tip, base,
            locks, snap_angles; for any, allow_nonphysical).
        backends: the generated code checked, numpy and C by default; the rows of a backend after the
            first are named ``<quantity> (<backend>)``.
        coriolis_matrix: check C (default: for chains of up to :data:`CORIOLIS_MATRIX_JOINTS` joints;
            its Christoffel symbols cost O(n^3) derivatives of M, minutes for a 10-joint arm).

    Raises:
        ModelError: bad model, a parallel model, a reference without the chain's joints or
            links, or Pinocchio missing.
    """
    from symkin import pipeline
    from symkin.runtime.loader import load

    pin = _pinocchio()
    path = Path(path)
    reference_path = Path(reference_urdf) if reference_urdf is not None else None
    model, text, reduction, mjcf = _sources(path, reference_path, urdf or {})
    with_c = bool(model.bodies) and (len(model.joints) <= CORIOLIS_MATRIX_JOINTS if coriolis_matrix is None
                                     else coriolis_matrix)
    # without gravity and springs G is identically zero and not emitted
    weighted = any(g != 0 for g in model.gravity) or bool(model.springs)
    dynamics = tuple(name for name in DYNAMICS_OUTPUTS if weighted or name != "gravity_vector")
    outputs = KINEMATICS_OUTPUTS + (dynamics + (("coriolis_matrix",) if with_c else ())
                                    + (("friction",) if model.friction else ()) if model.bodies else ())
    say = progress or (lambda _line: None)
    say(f"deriving {', '.join(outputs)} of {model.name} ({', '.join(backends)})")
    request = pipeline.resolve_request(model, outputs, ",".join(backends), None, False, "none")
    with tempfile.TemporaryDirectory(prefix="symkin-crosscheck-") as directory:
        written = pipeline.write(pipeline.generate(model, request), directory)
        generated = {backend: load(written, backend) for backend in backends}
        reference = pin.buildModelFromXML(text)
        data = reference.createData()
        # the reference reads the file's own names (a URDF's joint_0.0, renamed joint_0_0 in the model)
        joint_names = [model.source_name("joints", j.name) for j in model.joints]
        link_names = {j.link: model.source_name("links", j.link) for j in model.joints}
        missing = [name for name in joint_names if not reference.existJointName(name)]
        missing += [link for link in [reduction.base, reduction.tip, *link_names.values()]
                    if not reference.existFrame(link)]
        if missing:
            source = str(reference_path or path)
            raise ModelError([Problem(source, None, None, "", f"the reference has no joint or link "
                                                              f"{', '.join(sorted(set(missing)))}",
                                      "give a reference URDF of the same robot (--reference-urdf)")])
        chain = [reference.joints[reference.getJointId(name)] for name in joint_names]
        for actuator in (a for a in model.actuators if not a.gyroscopic):  # reflected N^2 J_m: Pinocchio's armature
            joint = reference.joints[reference.getJointId(model.source_name("joints", actuator.joint))]
            reference.armature[joint.idx_v] = float(actuator.reflected_inertia.xreplace(model.parameter_values))
        frame_links = {f"frame {link_names[j.link]}": j.link for j in model.joints}
        columns = [joint.idx_v for joint in chain]
        # joints that mimic others: the reference's joints are free, set at theta = A q + b (and A qd, A qdd)
        coupling = _coupling(model)
        shift = np.array([0.0 if j.coupling is None else float(j.coupling.offset.xreplace(model.parameter_values))
                          for j in model.joints])
        q_rest = pin.neutral(reference)
        for name, value in reduction.locked.items():
            if reference.existJointName(name):
                _set(q_rest, reference.joints[reference.getJointId(name)], value)
        base, tip = _link_frame(pin, reference, reduction.base), _link_frame(pin, reference, reduction.tip)
        pin.framesForwardKinematics(reference, data, q_rest)
        base_rotation = data.oMf[base].rotation.copy()  # the chain's base does not move: joints above it are locked
        gravity = np.array([float(g.xreplace(model.parameter_values)) for g in model.gravity])
        reference.gravity = pin.Motion(np.concatenate([base_rotation @ gravity, np.zeros(3)]))
        # V from a model without gravity: nonLinearEffects - G would lose V's digits under a large G
        weightless = pin.Model(reference)
        weightless.gravity = pin.Motion.Zero()
        weightless_data = weightless.createData()
        total_mass = float(sum(float(b.mass.xreplace(model.parameter_values)) for b in model.bodies))
        # the reference's friction is URDF's: one sign(qd) level per joint
        beyond_urdf = any(f.smoothing_velocity is not None or f.asymmetric for f in model.friction)
        springs = _SpringTorques(model)  # a URDF has no springs: the reference's are the model's, k (theta - theta_0)
        Q, QD, QDD = _states(model, samples, seed)
        say(f"comparing at {samples} states with Pinocchio {pin.__version__}")
        values = {backend: _evaluate(ours, outputs, Q, QD, QDD) for backend, ours in generated.items()}
        errors: dict[str, float] = {}
        rotate = np.kron(np.eye(2), base_rotation.T)
        for k in range(samples):
            q, v, a = q_rest.copy(), np.zeros(reference.nv), np.zeros(reference.nv)
            for joint, angle, rate, acceleration in zip(chain, coupling @ Q[k] + shift, coupling @ QD[k],
                                                        coupling @ QDD[k]):
                _set(q, joint, angle)
                v[joint.idx_v], a[joint.idx_v] = rate, acceleration
            pin.framesForwardKinematics(reference, data, q)
            to_base = data.oMf[base].inverse()
            want: dict[str, tuple[Any, ...]] = {"fk": ((to_base * data.oMf[tip]).homogeneous,)}
            for row, link in frame_links.items():
                frame = _link_frame(pin, reference, link_names[link])
                want[row] = ((to_base * data.oMf[frame]).homogeneous,)
            jacobian = np.reshape(pin.computeFrameJacobian(reference, data, q, tip,  # 1-D where nv = 1
                                                           pin.ReferenceFrame.LOCAL_WORLD_ALIGNED), (6, reference.nv))
            want["jacobian_geometric"] = (rotate @ jacobian[:, columns] @ coupling,)
            for row, link in frame_links.items():
                frame = _link_frame(pin, reference, link_names[link])
                jacobian = np.reshape(pin.computeFrameJacobian(reference, data, q, frame,
                                                               pin.ReferenceFrame.LOCAL_WORLD_ALIGNED), (6, reference.nv))
                want["frame_jacobians " + row[len("frame "):]] = (rotate @ jacobian[:, columns] @ coupling,)
            if model.bodies:
                want |= _dynamics_references(pin, reference, data, weightless, weightless_data, q, v, a, columns,
                                             coupling, total_mass, float(np.linalg.norm(gravity)), beyond_urdf, with_c,
                                             springs(coupling @ Q[k] + shift))
                if not weighted:
                    del want["gravity_vector"]
            for backend, got in values.items():
                suffix = "" if backend == backends[0] else f" ({backend})"
                for name, (expected, *scales) in want.items():
                    error = _normwise(_ours(got, name, k, frame_links, QD[k]), expected, *scales)
                    errors[name + suffix] = max(errors.get(name + suffix, 0.0), error)
    if model.bodies and mjcf:
        from symkin.references.mujoco_reference import mujoco_errors

        say("comparing M and V + G with MuJoCo on the MJCF file")
        for backend, got in values.items():
            suffix = "" if backend == backends[0] else f" ({backend})"
            for name, error in mujoco_errors(path, model, reduction.locked, got, Q, QD, _normwise).items():
                errors[name + suffix] = error
    comparisons = [Comparison(name, error) for name, error in errors.items()]
    if model.bodies and not with_c:
        comparisons.append(Comparison("coriolis_matrix", 0.0, "skipped: not asked for (--coriolis-matrix checks it)"))
    if model.bodies and beyond_urdf:
        comparisons.append(Comparison("friction", 0.0, "skipped: smoothed (tanh) or direction-dependent Coulomb "
                                                       "friction; Pinocchio's is one sign(qd) level"))
        comparisons.append(Comparison("inverse_dynamics", 0.0, "skipped: smoothed (tanh) or direction-dependent "
                                                               "Coulomb friction; Pinocchio's is one sign(qd) level"))
    if not model.bodies:
        comparisons.append(Comparison("dynamics", 0.0, "skipped: the model declares no bodies"))
    reference_name = f"Pinocchio {pin.__version__}"
    if model.bodies and mjcf:
        import mujoco

        reference_name += f" and MuJoCo {mujoco.__version__}"
    return CrosscheckReport(model.name, reference_name, samples, tolerance, tuple(comparisons))


def _evaluate(ours: Any, outputs: tuple[str, ...], Q: np.ndarray, QD: np.ndarray, QDD: np.ndarray) -> dict[str, Any]:
    """Every output of one backend's generated module at the sampled states."""
    arguments = {"mass_matrix": (Q,), "coriolis_vector": (Q, QD), "coriolis_matrix": (Q, QD), "gravity_vector": (Q,),
                 "friction": (QD,), "inverse_dynamics": (Q, QD, QDD)}
    return {name: getattr(ours, name)(*arguments.get(name, (Q,))) for name in outputs}


def _ours(values: dict[str, Any], row: str, k: int, frame_links: dict[str, str], qd: np.ndarray) -> np.ndarray:
    """symkin's value of the row ``row`` at state ``k`` (velocities ``qd``; ``frame_links``: {frame row:
    model link}; the Coriolis matrix is checked through its properties)."""
    if row in frame_links:
        frames = values["frames"]  # a one-joint chain's frames function returns its one frame as an array
        return frames[k] if isinstance(frames, np.ndarray) else getattr(frames, f"base_T_{frame_links[row]}")[k]
    if row.startswith("frame_jacobians "):
        jacobians = values["frame_jacobians"]  # (one array for a one-joint chain, as frames)
        link = frame_links["frame " + row[len("frame_jacobians "):]]
        return jacobians[k] if isinstance(jacobians, np.ndarray) else getattr(jacobians, f"base_J_{link}")[k]
    if row == "coriolis_matrix C qd":
        return values["coriolis_matrix"][k] @ qd
    if row == "coriolis_matrix Mdot - 2C skew":
        C = values["coriolis_matrix"][k]
        return C + C.T  # the reference gives Mdot = C_ref + C_ref^T: Mdot - 2C is skew iff C + C^T = Mdot
    return values[row][k]


def _dynamics_references(pin: Any, reference: Any, data: Any, weightless: Any, weightless_data: Any,
                         q: np.ndarray, v: np.ndarray, a: np.ndarray, columns: list[int], coupling: np.ndarray,
                         total_mass: float, gravity: float, beyond_urdf: bool, with_c: bool,
                         spring: np.ndarray) -> dict[str, tuple[Any, ...]]:
    """{row: (reference value, the magnitudes summed into it, natural size)} of the dynamics at one state.

    The natural size is the scale the quantity's terms have even where they cancel or vanish (V at
    qd = 0 is exactly 0 in symkin, 1e-27 in Pinocchio's recursion): ||M|| |qd|^2 for V, ||M|| |qd| for
    C, g sqrt(||M|| m) (about m g L) plus the springs' |k (theta - theta_0)| for G, their sum with ||M|| |qdd| and
    the friction for tau.  ``spring``: the joints' spring torques, added to G and tau (a URDF has none).
    """
    mass = np.reshape(pin.crba(reference, data, q), (reference.nv, reference.nv))  # a scalar where nv = 1
    mass = np.triu(mass) + np.triu(mass, 1).T
    M, M_terms = _reduced(coupling, mass[np.ix_(columns, columns)])
    size = float(np.linalg.norm(M_terms))
    qd, qdd = np.linalg.norm(coupling.T @ v[columns]), np.linalg.norm(coupling.T @ a[columns])
    damping, dry = reference.damping[columns], reference.friction[columns]
    friction_joint = damping * v[columns] + dry * np.sign(v[columns])
    friction_size = float(np.linalg.norm(np.abs(damping * v[columns]) + np.abs(dry)))
    G, G_terms = _reduced(coupling, np.atleast_1d(pin.computeGeneralizedGravity(reference, data, q))[columns] + spring)
    V, V_terms = _reduced(coupling, np.atleast_1d(pin.nonLinearEffects(weightless, weightless_data, q, v))[columns])
    g_size = gravity * math.sqrt(size * total_mass) + float(np.linalg.norm(spring))
    rows: dict[str, tuple[Any, ...]] = {
        "mass_matrix": (M, M_terms),
        "gravity_vector": (G, G_terms, g_size),
        "coriolis_vector": (V, V_terms, size * qd ** 2),
    }
    if with_c:
        coriolis = np.reshape(pin.computeCoriolisMatrix(weightless, weightless_data, q, v),
                              (reference.nv, reference.nv))[np.ix_(columns, columns)]
        Mdot, Mdot_terms = _reduced(coupling, coriolis + coriolis.T)
        rows["coriolis_matrix C qd"] = (V, V_terms, size * qd ** 2)
        rows["coriolis_matrix Mdot - 2C skew"] = (Mdot, Mdot_terms, size * qd)
    if (np.any(damping) or np.any(dry)) and not beyond_urdf:
        rows["friction"] = (*_reduced(coupling, friction_joint), friction_size)
    if not beyond_urdf:
        tau = np.atleast_1d(pin.rnea(reference, data, q, v, a))[columns] + friction_joint + spring
        rows["inverse_dynamics"] = (*_reduced(coupling, tau), size * (qdd + qd ** 2) + g_size + friction_size)
    return rows


class _SpringTorques:
    """k_j (theta_j - theta_0,j) of the model's joint springs at the joint values theta (0 on joints without)."""

    def __init__(self, model: Any):
        springs = {s.joint: s for s in model.springs}
        values = model.parameter_values
        self.stiffness = np.array([float(springs[j.name].stiffness.xreplace(values)) if j.name in springs else 0.0
                                   for j in model.joints])
        self.relaxed = np.array([float(springs[j.name].reference.xreplace(values)) if j.name in springs else 0.0
                                 for j in model.joints])

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        return self.stiffness * (theta - self.relaxed)


def _set(q: np.ndarray, joint: Any, value: float) -> None:
    """Set a Pinocchio configuration's entries of a one-coordinate joint (a continuous joint
    stores cos and sin)."""
    if joint.nq == 2:
        q[joint.idx_q:joint.idx_q + 2] = [math.cos(value), math.sin(value)]
    else:
        q[joint.idx_q] = value
