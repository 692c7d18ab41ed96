"""suvtwin: open, reproducible ground truth for vehicle state estimation.

Layers (each a subpackage; data flows one way, checked by import-linter in CI):

- ``suvtwin`` (this root: :mod:`suvtwin.errors`, :mod:`suvtwin.files`, the ``.tir``
  reader :mod:`suvtwin.tir`, and the equations several layers evaluate:
  :mod:`suvtwin.quarter_car_law`, :mod:`suvtwin.tire_stiffness`) and
  :mod:`suvtwin.roads` (ISO 8608 roads) at the bottom;
- :mod:`suvtwin.mjcf` (the MuJoCo SUV), :mod:`suvtwin.estimators` and
  :mod:`suvtwin.identification` side by side above them (estimators,
  identification and roads never import MuJoCo);
- :mod:`suvtwin.pipeline` (scenarios, simulator, campaigns, reports, CLI) on top.
"""
