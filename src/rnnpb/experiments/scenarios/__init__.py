"""What the studies run and measure: their scenarios, measures and starting models.

A study in :mod:`rnnpb.experiments.studies` is a runner, a judge and a report; the scripted
users it plays, the jobs its worker processes run and the measures it takes live here, one
module per study and part (``teaching_*`` for ``rnnpb study teach``, ``incremental_*`` for
``rnnpb study incremental``), with :mod:`~rnnpb.experiments.scenarios.study_models` finding or
learning the models a study starts from.
"""
