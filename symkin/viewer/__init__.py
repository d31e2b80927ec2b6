"""The interactive 3D page of a mechanism (``symkin view``): see :mod:`symkin.viewer.page`."""
