"""Kinematics of parallel mechanisms: loop closure, closed-form IK/FK, Jacobians, singularities (seed sec. 3.2, 4.2)."""
