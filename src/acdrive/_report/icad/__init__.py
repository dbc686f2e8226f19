"""The sections of the ICAD reproduction report, one module per section of the papers
(Ugalde-Loo et al., seed 001; Amezquita-Brooks et al., seed 002), assembled in report order by
``acdrive._report.icad_reproduction``; ``common`` and ``stator_matrix`` hold what several
sections share.
"""
