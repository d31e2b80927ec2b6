"""Identification of a device's dynamic parameters from a run (issue 33, docs/identification.md): one job, one
package (issue 62).

The parts of ``symkin identify`` and ``symkin excite``, in the order a run goes through them:
:mod:`~symkin.identification.excitation` (the excitation trajectory that conditions the base regressor; legs
without closed forms through :mod:`~symkin.identification.closure_excitation`),
:mod:`~symkin.identification.device_regressors` (the regressors of what a run records: the device's actuated
joints), :mod:`~symkin.identification.estimation` (reading the run, least squares, the energy balance,
validation), :mod:`~symkin.identification.consistent` (physically consistent standard parameters),
:mod:`~symkin.identification.implied_parameters` (the standard parameters a base estimate implies and what a model
file holds) and :mod:`~symkin.identification.identified_model` (the model file rewritten with the identified
values).
"""
