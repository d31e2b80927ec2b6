"""Tolerances of the test suite, each derived from the error analysis of what it checks.

Model of the arithmetic (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed.,
secs. 2.2 and 3.1): ``EPS`` = 2^-52 is the spacing of doubles at 1 and u = EPS/2 the unit
roundoff.  +, -, *, / and sqrt are correctly rounded (relative error <= u); glibc's sin, cos,
atan2, acos and exp are within 1 ulp (relative error <= EPS) but not correctly rounded, so
their last bit may differ between code paths (numpy's SIMD loops with or without AVX-512,
libm's scalar calls).  A sum or dot product of k terms in any order, with or without fused
multiply-adds (FMA contraction in compiled C), has an absolute error <= gamma_k * sum |terms|,
gamma_k = k u / (1 - k u) ~ k u (Higham eq. 3.4).  Two evaluations of one quantity (two
backends, CSE or not, folded parameters or not, one CPU or another) therefore agree to the
sum of their two bounds.

Every tolerance below is ``ulps * EPS`` times a scale the test states (the magnitude of the
terms: 1 for rotation entries and unit vectors, the reach for positions, the largest entry of
a matrix output), with the rounding count ``ulps`` derived in its comment and rounded up to a
power of two.  None is fitted to the digits one CPU printed: a failure means an error larger
than the arithmetic allows, whatever the machine.
"""

from __future__ import annotations

import numpy as np

#: 2^-52 = 2.2e-16.
EPS = float(np.finfo(np.float64).eps)

#: A hand-written closed form of a few operations (the seed's 2R FK x = l1 c1 + l2 c12, a rotation
#: about one axis, a norm of a 3-vector) against the generated code or against itself computed
#: another way: each side makes <= 2 libm calls (1 ulp each) and <= 4 correctly rounded operations
#: (u each) on terms of at most the scale: <= 2 EPS + 2 EPS = 4 EPS per side, 8 EPS for the two.
CLOSED_FORM = 8 * EPS

#: Kinematics (FK, frames, Jacobians, loop-closure residuals) of chains of <= 8 joints, two
#: evaluations compared.  Each joint transform's entries carry <= 2 EPS (sin/cos 1 ulp, a product
#: u, a sum u); each product of two 4x4 transforms adds gamma_4 ~ 2 EPS times sum |terms|, which is
#: <= 1 in a rotation block (a unit row times a unit column) and <= the reach in the translation
#: column; a Jacobian column is one more cross product (gamma_2).  8 joints: <= 8 x 4 = 32 EPS per
#: evaluation, 64 EPS for two, times the scale (1 for rotations, the reach for positions).
KINEMATICS = 64 * EPS

#: Dynamics (M, V, G, energies, inverse dynamics, TCP forces) of chains of n <= 7 bodies, two
#: evaluations compared, relative to the largest entry of the output.  An entry is a sum of <= n^2
#: composite-inertia terms, each a product of <= 2n kinematic entries (KINEMATICS / 2 each) and
#: inertia parameters: <= n^2 + 4n ~ 80 roundings per side relative to sum |terms|; M is positive
#: definite, so |M_ij| <= sqrt(M_ii M_jj) <= max |M| and sum |terms| stays within 2 max |M| for the
#: chains' inertia terms, of one sign per entry up to the off-diagonal couplings.  2 x 80 x 2 = 320
#: ulps, rounded up to 512.
DYNAMICS = 512 * EPS


def svd(n: int) -> float:
    """Two backward-stable SVDs of an n x n matrix (LAPACK's, ours): each computes the exact singular
    values of J + E with ||E||_2 <= p(n) u ||J||_2, p(n) ~ 4n for n <= 6 (LAPACK Users' Guide
    sec. 4.9.1), so a singular value moves by <= 4n u sigma_max per side: 4n EPS for the two, relative
    to sigma_max.  1/kappa = sigma_min / sigma_max, both relative to sigma_max, then within 8n EPS."""
    return 8 * n * EPS


#: A converged Newton iteration on loop-closure equations stops at the rounding level of evaluating
#: the residual (a kinematic chain: KINEMATICS / 2 of its scale); the iteration may end one step
#: short of the fixed point, which doubles it: KINEMATICS.
NEWTON = KINEMATICS

#: Forward kinematics and dynamics on paths into singular configurations (the stability harness's
#: normwise relative error): the UR10e's generated code divides by nothing, so its error does not
#: grow with kappa; it is the rounding of evaluation depth ~ 2n = 12 ulps of each output's largest
#: term, normwise over an output whose entries may cancel, with a factor 2 for the reference's
#: double-double rounding and the norm: 32 EPS = 7e-15.  A division by a singular matrix would
#: give kappa x EPS >= 2e-6 at the paths' ends (kappa > 1e10): five orders of magnitude above.
FORWARD_AT_SINGULARITIES = 32 * EPS

#: mpmath finite differences at d >= 40 digits with step h = 1e-15 (central differences): truncation
#: h^2 / 6 |f'''| ~ 1e-31 for entries of size <= the reach (~1.8 m for the UR10e), plus the
#: cancellation of d-digit values, 10^-d / h <= 1e-25.  1e-20 is five orders above both and four
#: below the float64 rounding (1e-16) that a wrong reference would show.
MPMATH_FINITE_DIFFERENCE = 1e-20

#: The scale of the UR10e's positions and Jacobian entries (metres): below the sum of its DH lengths,
#: d1 + |a2| + |a3| + d4 + d5 + d6 = 1.78 m (models/ur10e.yaml).
UR10E_SCALE = 2.0

#: The scale of the example DELTA's positions (metres): r_base + a + b = 0.32 m (models/delta.yaml).
DELTA_SCALE = 0.32

#: The scale of the example Stewart platform's lengths (metres): legs of at most 0.32 m (their stroke
#: in models/stewart.yaml), joint radii below 0.2 m; 0.5 m bounds both.
STEWART_SCALE = 0.5

#: The scale of the example pantograph's positions (metres): d/2 + l + L = 0.179 m (models/pantograph.yaml).
PANTOGRAPH_SCALE = 0.2
