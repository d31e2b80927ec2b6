"""Analyses of generated models: workspace, conditioning, global indices (seed sec. 4.1-4.3, 5.2).

Free functions of a loaded model (``symkin.load(directory, backend)``) and arrays; the
hot paths call the generated functions on whole batches and never touch sympy::

    import symkin
    from symkin import analysis

    arm = symkin.load("generated/planar_2r")
    result = analysis.gci(arm, method="qmc", samples=2**14, seed=0)
    print(result.value, result.measure)          # GCI +- error, area +- error

Modules: :mod:`~symkin.analysis.workspace` (point clouds,
occupancy, boundary), :mod:`~symkin.analysis.global_indices` (GCI eq. 8.28 and workspace measure
over joint or Cartesian domains), :mod:`~symkin.analysis.grids` (reachability and 1/kappa maps on
Cartesian grids), :mod:`~symkin.analysis.inverse` (which inverse kinematics a model gets: planar 2R closed form,
parallel closed forms), :mod:`~symkin.analysis.orientations` (a spherical platform's orientation
workspace and GCI, with the invariant measure of SO(3)), :mod:`~symkin.analysis.plots` (figures),
:mod:`~symkin.analysis.convergence` (run time against error).  The conditioning of Jacobians
(:mod:`symkin.numerics.conditioning`: singular values, 1/kappa, Table 8.5 criteria, characteristic length) and
the reachability interface (:mod:`symkin.mechanism.feasibility`) live below the analyses; the integrators beside them
(:mod:`symkin.integration`: grid, Monte Carlo, quasi-Monte Carlo, adaptive); their public names are exported here too.
The rating of a haptic device is :mod:`symkin.rating`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from symkin.lazy import lazy_exports

if TYPE_CHECKING:  # the names as the type checker sees them
    from symkin.numerics.conditioning import (
        characteristic_length,
        condition_number,
        frobenius_condition_number,
        homogenize,
        inverse_condition_number,
        inverse_frobenius_condition_number,
        manipulability,
        singular_values,
        transmission_indices,
    )
    from symkin.integration.estimates import Estimate, IntegralEstimate
    from symkin.mechanism.feasibility import InverseKinematics, feasible_configurations, reachable
    from symkin.analysis.global_indices import GlobalIndex, gci, global_index, workspace_measure
    from symkin.analysis.grids import index_grid, reachability_grid
    from symkin.integration.integrators import INTEGRATORS, integrate
    from symkin.analysis.inverse import closed_form_inverse
    from symkin.analysis.workspace import Occupancy, WorkspaceCloud, occupancy_from_cloud, sample_workspace
    from symkin.mechanism.reach import bounding_box

#: Each public name and the module that defines it: imported when first asked for (PEP 562), so that importing one
#: light module of the package (:mod:`~symkin.mechanism` for a command line parser) imports no other.
_EXPORTS = {name: module for module, names in (
    ("symkin.numerics.conditioning", ("characteristic_length", "condition_number", "frobenius_condition_number", "homogenize",
                      "inverse_condition_number", "inverse_frobenius_condition_number", "manipulability",
                      "singular_values", "transmission_indices",)),
    ("symkin.integration.estimates", ("Estimate", "IntegralEstimate",)),
    ("symkin.mechanism.feasibility", ("InverseKinematics", "feasible_configurations", "reachable",)),
    ("global_indices", ("GlobalIndex", "gci", "global_index", "workspace_measure",)),
    ("grids", ("index_grid", "reachability_grid",)),
    ("symkin.integration.integrators", ("INTEGRATORS", "integrate",)),
    ("inverse", ("closed_form_inverse",)),
    ("workspace", ("Occupancy", "WorkspaceCloud", "occupancy_from_cloud", "sample_workspace",)),
    ("symkin.mechanism.reach", ("bounding_box",)),
) for name in names}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, globals(), _EXPORTS)
