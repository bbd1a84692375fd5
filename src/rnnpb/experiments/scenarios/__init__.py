"""The studies' scenarios and measures: library code under ``rnnpb study NAME``.

One module per study (``novelty``, ``safety``, ``dyad``), or per study and part
(``teaching_scenario``, ``teaching_measures``, ``teaching_runs``, ``teaching_targets``;
``incremental_scenario``, ``incremental_measures``, ``incremental_runs``): what the study's
users do (generated streams, adversarial users, scripted subjects), the jobs that run them
through the mirror system, the measures taken of the runs, and the targets measured from them;
:mod:`~rnnpb.experiments.scenarios.study_models` finds or learns the models a study starts
from. A study's module in :mod:`rnnpb.experiments.studies` is a thin script over them: a
runner, a judge by its exam (:mod:`rnnpb.experiments.exams`) and a report.
"""
