"""Input validation, one leaf for every value a user gives: a scene's fields and a method's
options (:func:`number`, :func:`whole_number`, ..., each naming the field and the value as the
user wrote it), and a user's arrays.

For arrays: each function returns the library's own read-only
copy of what it was given, or raises the given error in one line naming the field and the
value. Nothing here reads past an array's stated bounds: a sparse matrix's index arrays are
checked in numpy (ranges, a non-decreasing ``indptr``, lengths that agree) before any
compiled routine of scipy reads them, since a malformed CSR crashes the interpreter there.

What is accepted, and how it is converted (exactly, or said where not):

- numbers as float64: floats (float16/32 exactly; longdouble rounded to double), integers
  (exactly up to 2⁵³), and object arrays whose every entry is a real number;
- refused with one line: complex values (a stiffness is real; pass ``.real`` if the imaginary
  parts are round-off), booleans, text, ``None`` and other objects, NaN and infinities, and
  entries whose size is outside what the arithmetic carries (0, or :data:`MAGNITUDE`'s range,
  as a scene's numbers are);
- sparse matrices in every scipy format, dense arrays and nested lists; the copy kept is CSR
  in canonical form (indices sorted, duplicates summed, explicit zeros dropped), so later
  steps never sort or sum in place, and the caller's arrays are never touched.
"""

from contactqp._validate.arrays import (
    MAX_ENTRIES,
    SHOWN,
    TINY,
    compressed,
    finite_in_range,
    frozen,
    index_vector,
    matrix,
    numbers,
    one_line,
    vector,
)
from contactqp._validate.scalars import (
    MAGNITUDE,
    flag,
    in_range,
    is_number,
    number,
    one_of,
    positive_number,
    positive_numbers,
    positive_values,
    shown,
    text,
    value_array,
    whole_number,
)

__all__ = [
    "MAGNITUDE", "MAX_ENTRIES", "SHOWN", "TINY", "compressed", "finite_in_range", "flag",
    "frozen", "in_range", "index_vector", "is_number", "matrix", "number", "numbers",
    "one_line", "one_of", "positive_number", "positive_numbers", "positive_values", "shown",
    "text", "value_array", "vector", "whole_number",
]
