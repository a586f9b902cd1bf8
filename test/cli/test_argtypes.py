"""The argument value types of the subcommands: what they accept and the reason they give."""

import argparse

import pytest

from rigid_rot_sim.cli import argtypes


@pytest.mark.parametrize(
    "convert, text, expected",
    [
        (argtypes.finite_number, "-2.5", -2.5),
        (argtypes.nonnegative_number, "0", 0.0),
        (argtypes.positive_number, "1e-9", 1e-9),
        (argtypes.positive_integer, "3", 3),
    ],
)
def test_accepted_values_come_back_converted(convert, text, expected):
    assert convert(text) == expected


@pytest.mark.parametrize(
    "convert, text, reason",
    [
        (argtypes.finite_number, "nan", "must be a finite number, got nan"),
        (argtypes.finite_number, "-inf", "must be a finite number, got -inf"),
        (argtypes.nonnegative_number, "-1e-300", "must be a finite number >= 0, got -1e-300"),
        (argtypes.nonnegative_number, "inf", "must be a finite number >= 0, got inf"),
        (argtypes.positive_number, "0", "must be a finite number > 0, got 0"),
        (argtypes.positive_number, "nan", "must be a finite number > 0, got nan"),
        (argtypes.positive_integer, "0", "must be >= 1, got 0"),
    ],
)
def test_refused_values_say_why(convert, text, reason):
    with pytest.raises(argparse.ArgumentTypeError, match=f"^{reason}$"):
        convert(text)
