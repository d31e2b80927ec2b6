"""A haptic device rated as its datasheet rates it (``symkin rate``; issue 62: one job, one package).

:mod:`~symkin.rating.formulas` (at one pose: apparent mass, peak force, position resolution, Coulomb friction
felt, gravity share, renderable stiffness), :mod:`~symkin.rating.forces` (isotropic and directional force from
the effort limits, seed Table 8.5), :mod:`~symkin.rating.handle_measures` (those measures at sampled poses of
a loaded model, with its actuators' data), :mod:`~symkin.rating.datasheet` (the measures over the usable
workspace and at the home pose, with where each extreme occurs) and :mod:`~symkin.rating.datasheet_files` (its
CSV and figure).
"""
