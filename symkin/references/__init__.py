"""Independent references a model is checked against (issue 62: one job per folder): the cross-check of a robot
file's generated kinematics and dynamics against Pinocchio (:mod:`~symkin.references.crosscheck`, ``symkin
crosscheck``) and an MJCF file's against MuJoCo's own (:mod:`~symkin.references.mujoco_reference`)."""
