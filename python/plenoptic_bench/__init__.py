# SPDX-License-Identifier: AGPL-3.0-or-later
"""Reproduce every figure in BENCHMARKS.md.

  tools/bench                 full run (about an hour on 2 cores); writes benchmarks/results/
  tools/bench --quick         tiny sizes, one run each: checks that the benchmark runs (CI)
  tools/bench --only trade    one section (overhead, lenses, trade, dark, threads, fullsize,
                              real_lens, fullsize_real_lens, realism, dataset, build)
  tools/bench --out DIR --report DIR/BENCHMARKS.md
                              a full run that leaves the committed results and report alone

Timings are medians of --runs runs (default 5; the overhead section takes at least 9) of
POV-Ray's own trace time; variants that are compared are run interleaved (A B C A B C ...) so
that drift of the machine affects them alike. Peak memory is the child's maximum resident set
size (getrusage). Where valgrind is installed, the overhead and lens-count sections also count
instructions with callgrind (single-threaded render): those counts repeat exactly whatever else
the machine is doing, unlike the wall clock (+-15 % between runs on a shared 2-core VM).
"""

# Package layout (tools/bench is its launcher; the package is a tool of this repository, not part
# of the plenoptic-lf distribution):
#   util       repository paths, logging, the machine's description
#   runner     Bench: renders with POV-Ray's trace time, CPU time and peak memory; scene worlds
#   callgrind  instruction counts of a render (valgrind's callgrind)
#   overhead, lenses, trade, dark, threads, fullsize, build   the sections (--only NAME)
#   real_lens  sections real_lens and fullsize_real_lens: a prescription main lens,
#              with the pass-fraction counts of source/bench/pass_fractions.cpp
#   report     BENCHMARKS.md from results.json; plots
#   cli        the command line (main)
