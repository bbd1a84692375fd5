"""The studies' scenarios and measures: library code under ``rnnpb study NAME``.

One module per study (``novelty``, ``safety``, ``dyad``, ``teach``, ``incremental``): what the
study's users do (generated streams, adversarial users, scripted subjects), the jobs that run
them through the mirror system, and the measures taken of the runs. A study's module in
:mod:`rnnpb.experiments.studies` is a thin script over them: a runner, a judge by its exam
(:mod:`rnnpb.experiments.exams`) and a report.
"""
