"""The work–precision benchmark of validation/BENCHMARKS.md, split by what each part holds.

``validation/bench_work_precision.py`` is the entry point (its ``run(quick, figures)`` is what
validation/benchmarks.py calls); this package holds its parts:

* the cases — :mod:`.cases` (the sweeps' tolerances, error levels, the scenes and initial
  states, fixed before any run) and :mod:`.records` (a sweep point, a case's record);
* the runners — :mod:`.timing` (least-of-repeats, the progress log), :mod:`.errors` (the error
  measures and the closed-form reference), :mod:`.our_side` (``cayley_heyoka.run`` swept and its
  stepping timed), :mod:`.peers` (scipy, REBOUND IAS15, mpmath), :mod:`.rotation_runs` and
  :mod:`.orbit_runs` (each case's runs);
* the report writers — :mod:`.report` (a case's Markdown and tables, the section),
  :mod:`.commentary` (the sentences built from a run's numbers), :mod:`.plots` (the figures).

It is imported as the top-level package ``work_precision_bench``: validation/ must be on
``sys.path`` (the entry script's directory is), which is also how its modules find the shared
validation modules (bench_common, rotation_cases, hamilton_planets).
"""
