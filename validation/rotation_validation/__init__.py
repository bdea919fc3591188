"""The rotation validation behind ``validation/rotation_report.py``, by what it holds.

The integrators of ``cayley_heyoka`` against the closed-form free rigid body (Cayley 1843,
``cayley_heyoka.reference.FreeRigidBody``).

* :mod:`.laws` — the round-off laws, their constants and the brief's requirements, fixed before
  any run (the cases themselves are the shared :mod:`rotation_cases`);
* :mod:`.exact_flow` — what the laws need from the exact flow of one case (sensitivities of the
  period and precession rate, extrema of the rates);
* :mod:`.runs` — one integration of one case at one precision and its measurements against the
  closed form (state, drifts, crossing times, growth exponents): the worker job ``run_job``;
* :mod:`.ensembles` — the growth-law ensembles (runs a few ulps apart) and their RMS fits;
* :mod:`.diagnostic` — the round-off diagnostic of long high-order 256-bit steps;
* :mod:`.plan` — the task list of a run with its load-balance costs, and the process pool;
* :mod:`.verdicts` — each run's judged rows against the laws;
* :mod:`.closed_forms` — Euler 1758 and Cayley 1846 against ``FreeRigidBody`` (a report
  section);
* :mod:`.figures` — the PNG plots; :mod:`.tables` — the Markdown tables and fixed texts;
  :mod:`.findings` — "What we learned", computed from the run; :mod:`.report` — the report
  section around them.

The modules import the shared validation modules (:mod:`rotation_cases`,
:mod:`report_sections`) by their plain names: ``validation/`` must be on ``sys.path`` (the entry
script's directory is).
"""
