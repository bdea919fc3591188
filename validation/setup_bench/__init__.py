"""The set-up cost and ensemble section of BENCHMARKS.md, behind ``validation/bench_setup.py``.

* :mod:`.cases` — the scenes and constants fixed before any run: the families of scenes of
  growing size, the patience level and step span, the cache scenes, the ensemble systems.
* :mod:`.results` — the measured records: :class:`Point` (one scene's compiles and step
  costs) and :class:`Throughput` (one ensemble method at one size).
* Runners: :mod:`.compiles` (cold compiles and step costs against size), :mod:`.cache_tiers`
  (a scene run through each level of caching, and in new processes), :mod:`.ensembles`
  (members per second of every ensemble method).
* Report writers: :mod:`.tables` (table rows), :mod:`.analysis` (the compact-mode threshold
  derived from the compile sweep), :mod:`.plots` (the two figures), :mod:`.section` (the
  section's Markdown, :func:`run`).
"""
