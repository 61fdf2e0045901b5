"""ErrorCollector.check keeps input errors and lets everything else through."""

from __future__ import annotations

import pickle

import pytest

from bikerider.errors import ErrorCollector, FileFormatError, FitError, InputError, InputErrors, ReachError


def test_check_keeps_input_errors_leaves_the_block_and_flattens_several():
    errors = ErrorCollector()
    reached = []
    with errors.check():
        raise InputError("w", -1.0, "a positive value")
    with errors.check():
        with errors.check():  # nested: the inner block keeps its own error
            raise InputErrors([InputError("c", 9.0, "at most 1 m"), InputError("rR", 0.0, "a positive value")])
        reached.append("after the inner block")
    with errors.check():
        reached.append("a block without an error runs to its end")
    assert [e.name for e in errors.errors] == ["w", "c", "rR"]
    assert reached == ["after the inner block", "a block without an error runs to its end"]
    with pytest.raises(InputErrors, match="3 input errors"):
        errors.raise_any()


def test_check_lets_other_exceptions_through():
    errors = ErrorCollector()
    with pytest.raises(ZeroDivisionError), errors.check():
        1 / 0  # noqa: B018
    with pytest.raises(KeyboardInterrupt), errors.check():
        raise KeyboardInterrupt
    assert not errors


@pytest.mark.parametrize(
    "error",
    [
        InputError("rear_frame.mass", -1.0, "a positive mass [kg]", "bike.toml"),
        InputErrors([InputError("w", -1.0, "positive"), InputError("c", 9.0, "below 1")]),
        ReachError("leg length", 0.3, "long enough to reach the pedals"),
        FileFormatError("records.csv", "no time column", 3),
        FitError("the period fit did not converge"),
    ],
)
def test_an_error_survives_the_way_back_from_a_worker_process(error):
    # the diagnosis fits candidates in worker processes; an error that cannot be unpickled stopped the pool
    back = pickle.loads(pickle.dumps(error))
    assert type(back) is type(error)
    assert str(back) == str(error)
