"""Results print as one short line (issue 25: ``print(sb.trajectory(...))``
dumped 30 KB, ``sb.motion`` returned a bare dict) and keep their field names."""

from __future__ import annotations

import dataclasses

import pytest

import stairbounce as sb


def test_trajectory_repr_is_one_short_line_with_the_counts():
    t = sb.trajectory(0.3, 0.2, steps=3)
    text = repr(t)
    assert "\n" not in text and len(text) < 150
    # the counts it prints are the lists' lengths (90 listed impacts: 30 a step)
    assert (len(t.impacts), len(t.accumulations), len(t.slides)) == (90, 3, 3)
    assert "90 impacts, 3 accumulations, 3 slides" in text and "steps=3" in text
    one = sb.trajectory(0.5, 0.9, steps=1)
    assert ", 1 impact," in repr(one) or "0 impacts" in repr(one)
    assert str(t) == text
    # a step with more impacts than max_listed: the rest is counted, not listed
    many = sb.trajectory(0.9, 0.05, steps=1, max_listed=5)
    assert many.unlisted and f"{sum(u.count for u in many.unlisted)} more impacts unlisted" in repr(many)


def test_motion_is_a_small_result_that_reads_like_the_dict_it_was():
    r = sb.motion(0.5, 0.8, steps=400, transient=400)
    assert isinstance(r, sb.Motion) and dataclasses.is_dataclass(r)
    text = repr(r)
    assert "\n" not in text and len(text) < 200 and "<k> = 0.26" in text
    for name in ("slides", "slide_step", "k_mean", "k_err", "jump_mean", "lyap1", "lyap1_err", "lyap2",
                 "lyap2_err", "lyap2_identity", "dissipation", "impulse", "speed_spread", "state_start",
                 "state_end", "steps", "transient"):
        assert r[name] == getattr(r, name) or r[name] != r[name]  # NaN-safe
        assert name in r
    assert dict(r)["k_mean"] == r.k_mean and r.get("nothing") is None
    with pytest.raises(KeyError):
        r["nothing"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.k_mean = 1.0
    s = sb.motion(0.1, 0.2, steps=10, transient=10)
    assert s.slides and repr(s) == f"Motion(e=0.1, u=0.2, 10 + 10 steps: slides on step {s.slide_step})"
