"""Benchmarks and studies: ``stt-codegen bench arenas | step | scaling | covering | alpha``.

* :mod:`.arenas` - the seeded random-arena generator (paper's Table I protocol, made explicit);
* :mod:`.planning`, :mod:`.astar`, :mod:`.rrtstar`, :mod:`.tracker` - the planner-plus-tracker
  baselines (networkx A*, OMPL RRT*, carrot following);
* :mod:`.arena_job`, :mod:`.arenas_bench`, :mod:`.parallel` - one arena per job, local
  processes or a Dask cluster;
* :mod:`.harness` - a generated C timing harness, compiled, timed and run under callgrind;
* :mod:`.step`, :mod:`.scaling` - the per-step cost and its growth;
* :mod:`.covering` - covering many polygons by boxes, and the design around them;
* :mod:`.alpha` - the implicit alpha step: Newton iterations, convergence in ``dt``;
* :mod:`.report` - statistics, tables and the machine description.

The ``bench`` subcommand's arguments are in :mod:`stt_codegen_bench.cli`.

Every benchmark measures what it compares side by side in one run and reports ratios;
the tests check structure and invariants, never speed; they count work where a
benchmark times it.
"""

__all__: list[str] = []
