"""Lagrangian dynamics of serial chains (seed sec. 4.4): M, C, V, G, friction, inverse and
forward dynamics, TCP forces, operational space and energies.

Importing :mod:`symkin.dynamics.quantities` registers the quantities (see its table).
"""
