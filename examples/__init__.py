"""The ``occsurf demo`` gallery: worked examples of each course chapter, written as PNG pictures
and STEP files. Not part of the library API; the library is :mod:`occsurf.algorithms` and
:mod:`occsurf.bridge`.

* :mod:`.gallery` — the registry :data:`DEMOS` and :func:`run_demos`;
* :mod:`.manipulation` (ch. 3-4), :mod:`.generation` (§6-26..6-33), :mod:`.curvenet`
  (§6-20..6-25), :mod:`.hierarchical` (ch. 5), :mod:`.fill` (§8-3), :mod:`.generalized` (§8-6, 8-7);
* :mod:`.hole_models` — models with n-sided holes built exactly in code (used by the fill demo,
  ``step_samples/make_holes.py``, the fill benchmark and the tests).
"""

from .gallery import DEMOS, run_demos

__all__ = ["DEMOS", "run_demos"]
