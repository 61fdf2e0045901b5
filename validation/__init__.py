"""Blind checks of the gap diagnosis and its next-experiment plan: research harnesses, not shipped.

Hidden truths simulated by a model that shares nothing with the candidate models but the benchmark
parameters (:mod:`validation.cases`), and the plan's blind check (:mod:`validation.plan_cases`).
Their users are ``docs/scripts/gap_*.py`` (``make docs``), ``bench/bench_gap.py`` and the gap tests;
they import this package from the repository root (it lives beside ``src/``, like ``derive/``, and is
not installed).
"""
