"""The IAS15 benchmark (``validation/bench_ias15.py``, section ``ias15`` of BENCHMARKS.md),
split by what it holds:

* ``case``: the orbit, its J2, the output grid, the scenes and the energy, fixed before any run;
* ``reference``: the real128 reference and its cache;
* ``results``: one method's run on the grid, its errors, exponents and least wall time;
* ``rebound_runs``: REBOUND's IAS15 with REBOUNDx's J2;
* ``prototypes``: the compensated-state and extended-precision prototypes (not in the library);
* ``encke_variants``: the Encke handler timed, and the two ``kepE`` diagnostics;
* ``runners``: the methods compared, the long run, the ensemble and the side measurements;
* ``plots``, ``report``, ``explanation``: the figures, the tables and the paragraphs.
"""
