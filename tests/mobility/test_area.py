"""Area value and the reflection fold that keeps every walk inside it."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uavcas.mobility import Area
from uavcas.mobility.area import reflect_into


def test_default_area_is_the_papers():
    a = Area()
    assert a.as_tuple() == (1000.0, 1000.0, 30.0, 110.0)
    assert a.clamp_altitude(25.96) == 30.0
    assert a.clamp_altitude(200.0) == 110.0
    assert a.clamp_altitude(50.0) == 50.0


def test_empty_band_is_refused():
    with pytest.raises(ValueError, match="altitude band"):
        Area(z_min_m=50, z_max_m=40)


def test_area_round_trips_json():
    a = Area(x_max_m=300, y_max_m=200, z_min_m=10, z_max_m=60)
    assert Area.model_validate_json(a.model_dump_json()) == a


@settings(max_examples=200, deadline=None)
@given(x=st.floats(-1e5, 1e5), lo=st.floats(-100, 100), width=st.floats(1.0, 500.0))
def test_reflection_lands_inside_and_is_a_mirror(x, lo, width):
    hi = lo + width
    y, flipped = reflect_into(np.array([x]), np.array([lo]), np.array([hi]))
    assert lo - 1e-6 <= y[0] <= hi + 1e-6
    # One reflection is the mirror image in the face crossed.
    # (Overshoots below float resolution may fold to the face itself without a flip.)
    if hi + 1e-9 < x <= hi + width - 1e-9:
        assert y[0] == pytest.approx(2 * hi - x, abs=1e-6) and flipped[0]
    if lo - width + 1e-9 <= x < lo - 1e-9:
        assert y[0] == pytest.approx(2 * lo - x, abs=1e-6) and flipped[0]
    if lo <= x < hi:
        assert y[0] == pytest.approx(x) and not flipped[0]
