"""The tolerances and runners of the orbit validation (validation/orbit_report.py).

* :mod:`.tolerances` — the round-off laws and the brief's requirements, fixed before any run
  (the cases themselves are the shared :mod:`orbit_cases`);
* :mod:`.runs` — one integration and its output columns as exact mpf values;
* :mod:`.departure` — the real128 Cartesian reference that carries the departure-point vector;
* :mod:`.reference`, :mod:`.long_runs`, :mod:`.sweeps` — the worker jobs of parts 1, 2 and 3–4
  and the comparisons of their results.

The report writers (tables, figures, text) are still in ``validation/orbit_report.py``.

The modules import the shared validation modules (:mod:`orbit_cases`, :mod:`report_sections`)
by their plain names: ``validation/`` must be on ``sys.path`` (the entry script's directory is).
"""
