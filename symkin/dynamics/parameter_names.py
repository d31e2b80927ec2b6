"""The names of the standard parameters of the dynamics regressors, in their order (no symbolic imports: the
identification analyses read them without loading symengine).

Per body (a serial chain's link, a parallel model's platform or actuated link; about a frame origin, Pinocchio's
order, ``Inertia::toDynamicParameters``): the mass, the first moment m c and the inertia about that origin.  Per
drive: the reflected rotor inertia I_a, the viscous, Coulomb and offset friction (tau += I_a qdd + f_v qd +
f_c sign(qd) + f_o).
"""

from __future__ import annotations

#: The ten standard inertial parameters of a body.
INERTIAL = ("m", "mx", "my", "mz", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz")
#: The parameters of a joint's drive: reflected rotor inertia, viscous, Coulomb, offset.
DRIVE = ("Ia", "fv", "fc", "fo")
#: The drive parameters whose efforts dissipate: an energy balance carries them as the integral of their power,
#: every other parameter as a change of the stored energy.
DISSIPATIVE = DRIVE[1:]
#: A parallel model's rods (``rod.<name>``): the masses lumped at their platform and proximal joints, and their
#: inertia across them beyond those ends' (I_c - m f (1 - f) L^2, of either sign).
ROD = ("mB", "mC", "dI")
#: The rods' parameters that are masses (never negative in a physical estimate).
ROD_MASSES = ROD[:2]
