"""The refill's choice between candidate fills (:class:`refill_candidates._Choice`): the best the
sequence of comparisons leaves (each candidate against the best before it, by its own rule:
``operator.lt`` on the score for central splits, ``_plate_wins`` for plates), found without
asking a folding candidate for its score as long as one candidate is fold-free: a central split
that folds is then never built in full (:func:`fold_free_fill`).

Hypothesis draws sequences of scores ``(folds, misses, worse)`` with either rule; the reference is
the sequential choice :func:`fitted_fill` made before, with every score known. Misses are drawn
from a few values so that ties (kept by ``<``, and by ``_plate_wins``' margin) occur.
"""

from __future__ import annotations

import operator

from hypothesis import given, settings
from hypothesis import strategies as st

from occsurf.bridge.modeling.refill_candidates import _Choice, _plate_wins


class _Fake:
    def __init__(self, score: tuple[bool, float, float], lazy: bool) -> None:
        self._score, self.lazy, self.asked = score, lazy, 0
        self.folds = score[0]

    @property
    def score(self) -> tuple[bool, float, float]:
        self.asked += 1
        return self._score


def _sequential(offered):
    best = None
    for rule, cand in offered:
        if best is None or rule(cand._score, best._score):
            best = cand
    return best


_scores = st.tuples(st.booleans(), st.sampled_from([1.0, 1.0, 1.05, 1.5, 2.0, 30.0]), st.sampled_from([0.1, 0.5, 2.0]))


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.booleans(), _scores), max_size=7))
def test_choice_is_the_sequential_best_and_spares_folding_candidates(seq) -> None:
    rules = {False: operator.lt, True: _plate_wins}
    cands = [(rules[plate], _Fake(score, lazy=score[0])) for plate, score in seq]
    choice = _Choice()
    for k, (rule, cand) in enumerate(cands):
        choice.offer(rule, cand)
        ref = _sequential(cands[:k + 1])
        # what fitted_fill's plate and wrap triggers read: a fold-free best, the same one
        assert (choice.fold_free is None) == (ref is None or ref.folds)
        if choice.fold_free is not None:
            assert choice.fold_free is ref
    assert choice.best is _sequential(cands)
    if any(not c.folds for _, c in cands):  # a fold-free candidate: no folding one was asked its score
        assert all(c.asked == 0 for _, c in cands if c.folds)


def test_choice_of_nothing_is_none() -> None:
    assert _Choice().best is None
