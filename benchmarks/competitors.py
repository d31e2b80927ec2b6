"""The same symkin model in Pinocchio and in SymForce, for side-by-side benchmarks.

Both are built from the loaded :class:`~symkin.model.Model` (joints as fixed operations
``before``/``after`` around the joint motion, bodies in link frames), with every parameter
at its default, so they compute the very mechanism symkin derived; bench_eval.py checks
that their poses agree with symkin's before timing anything.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import sympy

from symkin.model.schema import JointType, Model, Rotation


def _number(expr, values) -> float:
    return float(sympy.sympify(expr).xreplace(values))


def _rotation(axis, angle: float) -> np.ndarray:
    axis = np.asarray(axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def _ops_transform(ops, values) -> np.ndarray:
    """4x4 transform of a sequence of moving-frame operations."""
    T = np.eye(4)
    for op in ops:
        step = np.eye(4)
        if isinstance(op, Rotation):
            step[:3, :3] = _rotation([_number(a, values) for a in op.axis], _number(op.angle, values))
        else:
            step[:3, 3] = [_number(v, values) for v in op.vector]
        T = T @ step
    return T


def pinocchio_model(model: Model):
    """(pinocchio.Model, frame id of the TCP) of a serial symkin model."""
    import pinocchio as pin

    values = model.parameter_values
    pm = pin.Model()
    pm.gravity = pin.Motion(np.array([_number(g, values) for g in model.gravity]), np.zeros(3))
    bodies = {b.link: b for b in model.bodies}
    parent, pending = 0, _ops_transform(model.base, values)
    for joint in model.joints:
        placement = pending @ _ops_transform(joint.before, values)
        axis = np.array([_number(a, values) for a in joint.axis])
        offset = _number(joint.offset, values)
        motion = np.eye(4)
        if joint.type is JointType.REVOLUTE:
            motion[:3, :3] = _rotation(axis, offset)
            joint_model = pin.JointModelRevoluteUnaligned(axis)
        else:
            motion[:3, 3] = axis * offset
            joint_model = pin.JointModelPrismaticUnaligned(axis)
        placement = placement @ motion
        parent = pm.addJoint(parent, joint_model, pin.SE3(placement[:3, :3], placement[:3, 3]), joint.name)
        after = _ops_transform(joint.after, values)
        body = bodies.get(joint.link)
        if body is not None:
            inertia = pin.Inertia(_number(body.mass, values), np.array([_number(c, values) for c in body.com]),
                                  np.array(body.inertia.xreplace(values), dtype=float))
            pm.appendBodyToJoint(parent, inertia.se3Action(pin.SE3(after[:3, :3], after[:3, 3])), pin.SE3.Identity())
        pending = after
    tcp = pending @ _ops_transform(model.tcp, values)
    frame = pm.addFrame(pin.Frame("tcp", parent, pin.SE3(tcp[:3, :3], tcp[:3, 3]), pin.FrameType.OP_FRAME))
    return pm, frame


def symforce_fk_jacobian_codegen(model: Model, out_dir: Path) -> Path:
    """Generate SymForce C++ for (base_T_tcp 4x4, tangent-space Jacobian 6xn) of the TCP pose.

    Written as a SymForce user would: sf.Pose3 compositions of the joint operations and
    ``pose.jacobian(q)``; SymForce's own CSE and C++ printer do the rest.  Returns the
    directory holding the generated header.
    """
    import symforce

    symforce.set_epsilon_to_symbol()
    import symforce.symbolic as sf
    from symforce.codegen import Codegen, CppConfig

    values = model.parameter_values
    n = model.dof

    def ops_pose(ops):
        pose = sf.Pose3.identity()
        for op in ops:
            if isinstance(op, Rotation):
                axis = sf.V3(*[_number(a, values) for a in op.axis])
                pose = pose * sf.Pose3(R=sf.Rot3.from_angle_axis(_number(op.angle, values), axis), t=sf.V3())
            else:
                pose = pose * sf.Pose3(R=sf.Rot3.identity(), t=sf.V3(*[_number(v, values) for v in op.vector]))
        return pose

    def fk_jacobian(q: sf.Matrix):
        pose = ops_pose(model.base)
        for k, joint in enumerate(model.joints):
            axis = sf.V3(*[_number(a, values) for a in joint.axis])
            amount = q[k] + _number(joint.offset, values)
            if joint.type is JointType.REVOLUTE:
                motion = sf.Pose3(R=sf.Rot3.from_angle_axis(amount, axis), t=sf.V3())
            else:
                motion = sf.Pose3(R=sf.Rot3.identity(), t=axis * amount)
            pose = pose * ops_pose(joint.before) * motion * ops_pose(joint.after)
        pose = pose * ops_pose(model.tcp)
        return pose.to_homogenous_matrix(), pose.jacobian(q)

    codegen = Codegen.function(fk_jacobian, input_types=[sf.Matrix(n, 1)], config=CppConfig(),
                               name=f"{model.name}_fk_jacobian", output_names=["T", "J"])
    result = codegen.generate_function(output_dir=out_dir, skip_directory_nesting=True)
    headers = list(Path(result.generated_files[0]).parent.rglob("*.h")) if result.generated_files else []
    return headers[0].parent if headers else Path(out_dir)


def pinocchio_delta(v: dict[str, float], rod_inertia: float | None = None):
    """The DELTA of models/delta.yaml (parameter values ``v``) as a Pinocchio tree closed by three point
    constraints: (pin, model, constraints, legs), legs as (r_i, arm joint, rod joint, (rod end, B_i frames)).
    ``rod_inertia``: each rod's moment of inertia across it about its centre (default: its ends' m b^2 / 4).

    Tree: the platform on a translation joint (the parallelograms keep its orientation) with its mass;
    per leg the arm on a revolute joint about u_i = r_i x z at A_i (a uniform rod, and the rotor's
    gear^2 J_rotor about the axis), then the parallelogram as one rod on a universal joint at the elbow
    C_i (axes u_i and z) carrying m_rod/2 at each end (a rigid dumbbell has the kinetic energy of the
    model's rod halves lumped at C_i and B_i, exactly).  Each rod's end is held at the platform joint
    B_i = P + r_tcp r_i by a 3-D rigid constraint (Pinocchio's constraintDynamics: the KKT system with
    the loop multipliers, sharing no code with symkin's elimination through J)."""
    import pinocchio as pin

    model = pin.Model()
    z = np.array([0.0, 0.0, 1.0])
    platform = model.addJoint(0, pin.JointModelTranslation(), pin.SE3.Identity(), "platform")
    model.appendBodyToJoint(platform, pin.Inertia(v["m_platform"], np.zeros(3), np.zeros((3, 3))), pin.SE3.Identity())
    legs = []
    constraints = pin.StdVec_RigidConstraintModel()
    for i, phi in enumerate(np.radians([0.0, 120.0, 240.0])):
        r = np.array([np.cos(phi), np.sin(phi), 0.0])
        u = np.cross(r, z)
        across = np.eye(3) - np.outer(r, r)
        arm = model.addJoint(0, pin.JointModelRevoluteUnaligned(u), pin.SE3(np.eye(3), v["r_base"] * r), f"arm{i}")
        model.appendBodyToJoint(arm, pin.Inertia(v["m_arm"], v["a"] / 2 * r, v["m_arm"] * v["a"] ** 2 / 12 * across),
                                pin.SE3.Identity())
        model.appendBodyToJoint(arm, pin.Inertia(0.0, np.zeros(3), v["gear"] ** 2 * v["J_rotor"] * np.outer(u, u)),
                                pin.SE3.Identity())
        hinge = model.addJoint(arm, pin.JointModelRevoluteUnaligned(u), pin.SE3(np.eye(3), v["a"] * r), f"hinge{i}")
        swing = model.addJoint(hinge, pin.JointModelRevoluteUnaligned(z), pin.SE3.Identity(), f"swing{i}")
        across_rod = v["m_rod"] * v["b"] ** 2 / 4 if rod_inertia is None else rod_inertia
        model.appendBodyToJoint(swing, pin.Inertia(v["m_rod"], v["b"] / 2 * r, across_rod * across),
                                pin.SE3.Identity())
        constraints.append(pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, swing,
                                                    pin.SE3(np.eye(3), v["b"] * r), platform,
                                                    pin.SE3(np.eye(3), v["r_tcp"] * r), pin.ReferenceFrame.LOCAL))
        ends = (model.addFrame(pin.Frame(f"rod_end{i}", swing, 0, pin.SE3(np.eye(3), v["b"] * r), pin.FrameType.OP_FRAME)),
                model.addFrame(pin.Frame(f"B{i}", platform, 0, pin.SE3(np.eye(3), v["r_tcp"] * r), pin.FrameType.OP_FRAME)))
        legs.append((r, arm, swing, ends))
    return pin, model, constraints, legs


def constraint_dynamics_of(pin, model, constraints):
    """(data, constraint datas, settings) for ``pin.constraintDynamics(model, data, q, v, tau, constraints,
    datas, settings)`` on the closed DELTA of :func:`pinocchio_delta`: the exact KKT solve (mu = 0, one
    proximal iteration at 1e-14)."""
    data = model.createData()
    datas = pin.StdVec_RigidConstraintData()
    for c in constraints:
        datas.append(c.createData())
    pin.initConstraintDynamics(model, data, constraints, datas)
    return data, datas, pin.ProximalSettings(1e-14, 0.0, 1)


def delta_tree_state(pin, model, data, legs, v, P, theta, theta_d):
    """Tree coordinates of the assembled DELTA (rod angles from e_i = (B_i - C_i)/b, by hand) and the
    tree velocity whose arm rates are theta_d and whose point constraints hold (J_c v = 0)."""
    z = np.array([0.0, 0.0, 1.0])
    q = np.zeros(model.nq)
    q[:3] = P
    for (r, arm, swing, _), th in zip(legs, theta):
        C = v["r_base"] * r + v["a"] * (np.cos(th) * r + np.sin(th) * z)
        e = (P + v["r_tcp"] * r - C) / v["b"]
        q[model.joints[arm].idx_q] = th
        q[model.joints[arm].idx_q + 1] = np.arctan2(e @ z, e @ r) - th       # hinge: the rod's elevation
        q[model.joints[swing].idx_q] = np.arcsin(e @ np.cross(z, r))         # swing: its side angle
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    gap = max(np.linalg.norm(data.oMf[a].translation - data.oMf[b].translation) for *_, (a, b) in legs)
    if gap > 16 * np.finfo(float).eps * v["b"]:  # the tree closes at the configuration (a check of the angles above)
        raise ValueError(f"the Pinocchio DELTA does not close at P = {P}: gap {gap:.3g} m")
    J_c = np.vstack([pin.getFrameJacobian(model, data, a, pin.LOCAL_WORLD_ALIGNED)[:3]
                     - pin.getFrameJacobian(model, data, b, pin.LOCAL_WORLD_ALIGNED)[:3] for *_, (a, b) in legs])
    arms = [model.joints[arm].idx_v for _, arm, _, _ in legs]
    rest = [k for k in range(model.nv) if k not in arms]
    velocity = np.zeros(model.nv)
    velocity[arms] = theta_d
    velocity[rest] = np.linalg.solve(J_c[:, rest], -J_c[:, arms] @ theta_d)
    return q, velocity, arms
