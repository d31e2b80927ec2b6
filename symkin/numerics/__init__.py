"""Numerics below every mechanism: point sets in a box (:mod:`~symkin.numerics.sampling`, Sobol' points drawn
without scipy.stats, :mod:`~symkin.numerics.sobol`) and the transmission quality of Jacobians
(:mod:`~symkin.numerics.conditioning`: singular values, 1/kappa, the characteristic length).  Nothing here knows
a model: the run-time mechanism (:mod:`symkin.mechanism`) and the analyses build on them.
"""
