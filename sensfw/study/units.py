"""Values with units in study files: ``"7.05e5 N/mm"``, ``"5 kHz"`` (pint), or bare numbers
meaning the unit the model declares."""

from __future__ import annotations

import functools
import tokenize

from .schema import Quantity


@functools.cache
def units():
    """The pint unit registry (built once: it takes a moment)."""
    import pint

    return pint.UnitRegistry()


def to_unit(value: Quantity, unit: str) -> float:
    """``value`` ("7.05e5 N/mm", or a bare number meaning ``unit``) as a float in ``unit``."""
    if isinstance(value, bool):
        raise ValueError(f"expected a number or a quantity string, got {value!r}")
    if isinstance(value, (int, float)):
        return float(value)
    import pint

    try:
        try:  # "1e6": a bare number, in ``unit`` (pint reads it as dimensionless)
            return float(value.strip())
        except ValueError:
            pass
        q = units().Quantity(value.strip())
        if isinstance(q, (int, float)):
            return float(q)
        return float(q.to(unit or "dimensionless").magnitude)
    except pint.DimensionalityError:
        raise ValueError(f"cannot convert {value!r} to {unit or 'a plain number'}") from None
    except (pint.UndefinedUnitError, pint.errors.DefinitionSyntaxError, ValueError,
            AttributeError, TypeError, AssertionError, ArithmeticError, SyntaxError,
            tokenize.TokenError) as err:
        # pint's parser is Python's tokenizer: an unmatched bracket ("[", "5 Hz)") raises
        # TokenError, "1 / 0 Hz" ZeroDivisionError
        why = "unbalanced brackets" if isinstance(err, tokenize.TokenError) else err
        raise ValueError(f"cannot read {value!r} as a quantity in {unit or '1'}: {why}") \
            from None
