"""The blind-test protocol and statistics: pure logic, no rig."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from teleop.core.errors import InputError
from teleop.apps.protocols.blind.protocol import (HARDER, SOFTER, UNSURE, Compare, Rate, check_ratings, next_step,
                                             ranking_from_answers, ratings_from_positions)
from teleop.apps.protocols.blind.stats import SEED_TABLE3, average_ranks, kendall_tau, kendall_w, loading_slope, mean_std


def truthful(hardness):
    """Answer every question of the protocol from known hardness values; returns (answers, final step)."""
    n = len(hardness)
    answers = []
    step = next_step(n, answers)
    while isinstance(step, Compare):
        answers.append((step, HARDER if hardness[step.new] > hardness[step.ref] else SOFTER))
        step = next_step(n, answers)
    return answers, step


def test_seed_order_of_questions():
    answers, final = truthful([2.0, 3.0, 1.0, 4.0])
    # zones 1 and 2 first, then zone 3 against 1 and 2, then zone 4 against 1, 2, 3 (0-based here)
    assert [(s.new, s.ref) for s, _ in answers] == [(1, 0), (2, 0), (2, 1), (3, 0), (3, 1), (3, 2)]
    assert isinstance(final, Rate) and final.ranking == (3, 1, 0, 2)


@settings(max_examples=40)
@given(st.permutations(range(4)))
def test_truthful_answers_give_the_true_ranking(perm):
    hardness = np.array(perm, dtype=float)
    _, final = truthful(hardness)
    assert final.ranking == tuple(int(i) for i in np.argsort(-hardness))


def test_unsure_repeats_the_same_question_and_counts():
    answers = [(Compare(1, 0), UNSURE)]
    assert next_step(4, answers) == Compare(1, 0, 1)
    answers.append((Compare(1, 0, 1), UNSURE))
    assert next_step(4, answers) == Compare(1, 0, 2)
    answers.append((Compare(1, 0, 2), SOFTER))
    assert next_step(4, answers) == Compare(2, 0, 0)
    assert ranking_from_answers(4, answers) == (0, 1)


def test_inconsistent_answers_still_give_a_ranking_of_all_zones():
    # zone 3 says harder than zone 1 but softer than zone 2, while zone 1 > zone 2: a cycle
    answers = [(Compare(1, 0), SOFTER), (Compare(2, 0), HARDER), (Compare(2, 1), SOFTER)]
    r = ranking_from_answers(3, answers)
    assert sorted(r) == [0, 1, 2]


@settings(max_examples=60)
@given(st.lists(st.floats(0, 1), min_size=4, max_size=4), st.integers(8, 10), st.integers(1, 3))
def test_ratings_from_positions_always_follow_the_rules(pos, hard, soft):
    ratings = ratings_from_positions((0, 1, 2, 3), pos, hard, soft)
    check_ratings((0, 1, 2, 3), ratings)
    assert ratings[0] == hard and ratings[-1] == soft


@pytest.mark.parametrize("bad", [[7, 6, 5, 1], [10, 6, 5, 4], [10, 5, 6, 1], [10, 6, 6, 1], [10, 6, 1]])
def test_bad_ratings_are_refused(bad):
    with pytest.raises(InputError):
        check_ratings((0, 1, 2, 3), bad)


def test_kendall_tau_and_w():
    truth = ("a", "b", "c", "d")
    assert kendall_tau(truth, truth) == 1.0
    assert kendall_tau(truth[::-1], truth) == -1.0
    assert kendall_tau(("b", "a", "c", "d"), truth) == pytest.approx(4 / 6)
    same = np.tile([10, 7, 4, 2], (5, 1))
    assert kendall_w(same) == pytest.approx(1.0)
    # two raters in exactly opposite order: rank sums all equal, W = 0
    assert kendall_w(np.array([[1, 2, 3, 4], [4, 3, 2, 1]])) == pytest.approx(0.0)
    # the seed's Table 3 (rows = participants): near-perfect agreement
    table = np.array([row["ratings"] for row in SEED_TABLE3]).T
    assert kendall_w(table) == pytest.approx(1.0)


def test_average_ranks_match_scipy():
    from scipy.stats import rankdata

    rng = np.random.default_rng(0)
    for _ in range(20):
        row = rng.integers(1, 5, size=6)
        np.testing.assert_allclose(average_ranks(row), rankdata(row))


def test_table3_mean_and_std_reproduce_the_seed():
    for row in SEED_TABLE3:
        m, s = mean_std(row["ratings"])
        assert m == pytest.approx(row["mean"], abs=0.005)
        if row["colour"] != "white":
            assert s == pytest.approx(row["std"], abs=0.005)
    # the seed prints 0.80 for the white row, but its own ratings give 0.88 (ddof=1; 0.83 with ddof=0)
    assert mean_std(SEED_TABLE3[3]["ratings"])[1] == pytest.approx(0.876, abs=0.001)


def test_loading_slope_recovers_a_spring_and_ignores_unloading():
    x = np.r_[np.linspace(0, 0.004, 200), np.linspace(0.004, 0, 200)]
    k = 250.0
    f = np.where(np.arange(400) < 200, k * np.maximum(x - 0.001, 0), 0.5 * k * np.maximum(x - 0.001, 0))
    assert loading_slope(x, f) == pytest.approx(k, rel=0.01)
    assert loading_slope(x, np.zeros_like(x)) == 0.0
    assert loading_slope(x, np.full_like(x, 0.01)) == 0.0  # below the detection threshold


def test_loading_slope_ignores_a_force_felt_before_contact_and_a_bounce_back():
    k = 200.0
    x = np.linspace(0, 0.003, 300)
    f = k * np.maximum(x - 0.001, 0)
    # a stray force before contact (a friction-compensation residue, ~0.06 N for 40 samples)
    f_stray = f.copy()
    f_stray[:40] = 0.06
    assert loading_slope(x, f_stray) == pytest.approx(k, rel=0.05)
    # pushed back by 0.3 mm at 2 mm, then on again: the way back and the re-approach are not loading
    back = np.linspace(0.002, 0.0017, 30)
    x_b = np.r_[x[x <= 0.002], back, back[::-1], x[x > 0.002]]
    f_b = np.r_[f[x <= 0.002], np.full(30, k * 0.001), np.full(30, 0.6 * k * 0.001), f[x > 0.002]]
    assert loading_slope(x_b, f_b) == pytest.approx(k, rel=0.02)


def test_loading_slope_counts_only_the_last_contact_before_the_peak():
    # a stiff contact (500 N/m from 1.3 mm) after a blip in free travel: 0.1 N for 0.3 mm, then nothing
    # (the FSR's loading state crossing over at the press's reversal); the blip is not the pad
    k = 500.0
    x = np.linspace(0, 0.0019, 400)
    f = k * np.maximum(x - 0.0013, 0)
    blip = (x > 0.0004) & (x < 0.0008)
    f_blip = f.copy()
    f_blip[blip] = 0.1
    assert loading_slope(x, f_blip) == pytest.approx(k, rel=0.05)
    # a noisy soft press whose force only dips towards the threshold is one contact, not several
    rng = np.random.default_rng(0)
    x2 = np.linspace(0, 0.005, 500)
    f2 = 20.0 * np.maximum(x2 - 0.001, 0) + rng.normal(0, 0.004, x2.size)
    assert loading_slope(x2, f2) == pytest.approx(20.0, rel=0.15)
