"""The pieces of the Bodson reproduction report (``acdrive reproduce bodson``), assembled by
``acdrive._report.bodson_reproduction``: ``numbers`` (sections II-III), ``experiments`` (section
IV), ``verdicts`` (tolerances and claims) and ``discussion`` (where simulation and paper differ).
"""
