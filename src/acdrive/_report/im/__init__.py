"""The pieces of the IM time-domain reproduction report (Amezquita-Brooks et al., secs. VI-VIII;
``acdrive reproduce im``), assembled by ``acdrive._report.im_reproduction``: ``settings`` (the
experiments, printed numbers and tolerances), ``numbers`` (the runs and every number the report
prints), ``verdicts``, ``figures`` and ``sections``.
"""
