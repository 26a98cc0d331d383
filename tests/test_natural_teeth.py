"""The natural-tooth colour range derived from the published rows."""

import pytest
from dentalux import natural_teeth


def test_range_is_mean_plus_minus_two_sd_and_holds_the_other_studies():
    rng = natural_teeth.reference_range("mid-incisal")
    rows = {r["id"]: r for r in natural_teeth.rows()}
    mean, sd = rows["wee2023-enamel-infinite-mean"], rows["wee2023-enamel-infinite-sd"]
    for c in "Lab":
        assert rng[c] == pytest.approx((mean[c] - 2 * sd[c], mean[c] + 2 * sd[c]))
    # whole-tooth means of another study (no SD) fall inside the derived box
    for r in rows.values():
        if r["statistic"] == "mean" and None not in (r["L"], r["a"], r["b"]):
            assert natural_teeth.inside((r["L"], r["a"], r["b"]), rng), r["id"]
    assert not natural_teeth.inside((40.0, 0.0, 5.0), rng)  # the old dark incisor
    with pytest.raises(ValueError, match="region"):
        natural_teeth.reference_range("molar")
    c, h = natural_teeth.chroma_hue((70.0, 0.0, 10.0))
    assert c == pytest.approx(10.0) and h == pytest.approx(90.0)
