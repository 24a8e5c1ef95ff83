"""Values as IEC literals of their type (st.runtime.values.to_st_literal): what the online mode's
code view, watch list, trends and log and the reports show, and what a user can type back."""

from __future__ import annotations

import pytest

from st.model import types as T
from st.runtime.values import to_st_literal

E = T.EnumType(
    "TrafficPhase",
    {"cars_green": ("CARS_GREEN", 0), "cars_amber": ("CARS_AMBER", 1)},
    names_by_value={0: "CARS_GREEN", 1: "CARS_AMBER"},
)


@pytest.mark.parametrize(
    ("value", "t", "text"),
    [
        (40.0, T.REAL, "40.0"),  # not 4e+01
        (80.0, T.REAL, "80.0"),
        (0.1, T.REAL, "0.1"),
        (-2.5, T.REAL, "-2.5"),
        (3.4028234663852886e38, T.REAL, "3.4028235E38"),
        (1e30, T.LREAL, "1.0E30"),
        (1.5e-5, T.LREAL, "1.5E-5"),
        (123456.7, T.LREAL, "123456.7"),
        (1_500_000_000, T.TIME, "T#1s500ms"),
        (True, T.BOOL, "TRUE"),
        (255, T.BYTE, "255"),
        ("it's", T.StringType(80, False), "'it$'s'"),
    ],
)
def test_a_value_is_written_as_an_iec_literal_of_its_type(value, t, text):
    assert to_st_literal(value, t) == text


def test_an_enumeration_value_is_its_type_and_member():
    assert to_st_literal(1, E) == "TrafficPhase#CARS_AMBER"
