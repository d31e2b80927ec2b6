"""Integration of a vector integrand over a box, each estimate with its error (issue 62: one job, one package).

The GCI (seed eq. 8.28) and the workspace measure are ratios of integrals; what integrates them knows nothing of
mechanisms: :mod:`~symkin.integration.integrand` (a vectorized integrand over a box),
:mod:`~symkin.integration.integrators` (grid, Monte Carlo, quasi-Monte Carlo, adaptive, by name),
:mod:`~symkin.integration.adaptive` (Genz-Malik degree-7 cubature), :mod:`~symkin.integration.chunked` (the
integrators in chunks of points on Dask, budgets beyond memory) and :mod:`~symkin.integration.estimates` (values
with error estimates, ratios of integrals).  The analyses (:mod:`symkin.analysis.global_indices`) build the
integrands from a mechanism.
"""
