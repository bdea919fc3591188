"""The orbit validation (Cayley 1860) behind ``validation/orbit_report.py``, by what it holds.

* :mod:`.tolerances` — the round-off laws and the brief's requirements, fixed before any run
  (the cases themselves are the shared :mod:`orbit_cases`);
* :mod:`.runs` — one integration and its output columns as exact mpf values;
* :mod:`.departure` — the real128 Cartesian reference that carries the departure-point vector;
* :mod:`.reference`, :mod:`.long_runs`, :mod:`.sweeps` — the worker jobs of parts 1, 2 and 3–4
  and the comparisons of their results;
* :mod:`.plan` — the task list of a run with its load-balance costs;
* :mod:`.figures` — the PNG plots; :mod:`.tables` — the Markdown tables of each part;
  :mod:`.report` — the report section around them and its findings.

The modules import the shared validation modules (:mod:`orbit_cases`, :mod:`report_sections`)
by their plain names: ``validation/`` must be on ``sys.path`` (the entry script's directory is).
"""
