"""``python -m benchmarks [--quick] [--only NAME ...]``: the speed, memory and accuracy tables.

Every ``bench_*`` module registers its tables with :func:`benchmarks.harness.benchmark`; ``--only``
takes those names. Medians and spread are measured, ratios come from the same run, and nothing
here is asserted by a test. The real-face tools (``realfaces``: also ``--jitter``, ``--stress``,
``--mirror``; ``stress_clips``: the harder copies; ``real_clips``: reading ``../shared/real/``)
skip with one line when the shared clips are absent. ``soak_window`` drives the real
performance window for minutes.
"""
