"""Lagrangian dynamics of serial chains (seed sec. 4.4): M, C, V, G, friction, inverse and
forward dynamics, TCP forces, operational space and energies.

:mod:`symkin.dynamics.quantities` defines the quantities (see its table); the catalog
(:mod:`symkin.derivation.catalog`) lists it.
"""
