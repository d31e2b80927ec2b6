"""Serial-chain kinematics: frames, forward kinematics and Jacobians (seed sec. 3.1 and 4)."""
