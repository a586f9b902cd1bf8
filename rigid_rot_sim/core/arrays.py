"""The array types of the core: what a kernel or a public function takes and returns, by dtype.

numba compiles a kernel for the dtypes it is called with and ignores annotations, so these are
for the reader and for mypy: a kernel parameter says which array it wants (``FloatArray`` for a
float64 state, ``IntArray`` for int64 steps or status codes, ``BoolArray`` for masks) and a
scalar says ``float``, ``int`` or ``bool``. A public function that converts its input with
``np.asarray`` takes :data:`ArrayLike` (a sequence, a scalar or an array).

>>> import numpy as np
>>> x: FloatArray = np.zeros(3)
>>> x.dtype
dtype('float64')
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numpy.typing import ArrayLike

__all__ = ["ArrayLike", "BoolArray", "FloatArray", "IntArray"]

#: A float64 array (states, moments, torques, coefficients); numpy's typing keeps arithmetic on it float64.
FloatArray = npt.NDArray[np.float64]
#: An int64 array (step numbers, status codes, index tables).
IntArray = npt.NDArray[np.int64]
#: A boolean array (masks).
BoolArray = npt.NDArray[np.bool_]
