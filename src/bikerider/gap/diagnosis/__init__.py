"""The diagnosis: where the model misses, whether a candidate explains it, which one, and the
selection.

:func:`~bikerider.gap.diagnosis.result.diagnose` calls the steps in this order, each a function of
explicit inputs: ``compare`` (the records beside the tables; which candidates the data can try),
``where`` (gap map, gap test, and the verdict with the parameter test), ``which`` (ranking and pairs,
on the held-out ``folds``), ``priors`` (usual ranges, priors, friction's equivalent) and ``select``;
every fit and cross-validation goes through one cache (``fits``); ``statistics`` holds the tests they
share.  The result is a frozen :class:`~bikerider.gap.diagnosis.result.Diagnosis`.
"""
