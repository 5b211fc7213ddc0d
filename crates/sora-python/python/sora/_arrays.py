"""Array checks shared by the package: numpy inputs broadcast together,
flattened to the 1-D float arrays the native module takes, with one-line
``ValueError`` messages that name the arguments."""

from __future__ import annotations

from typing import Tuple

import numpy as np


def broadcast_flat(names: Tuple[str, ...], *values, dtype=float):
    """The arguments as numpy arrays broadcast to one shape, flattened
    (contiguous, ``dtype``), and that shape."""
    arrays = []
    for name, value in zip(names, values):
        try:
            arrays.append(np.asarray(value, dtype=dtype))
        except (TypeError, ValueError, OverflowError) as error:
            # OverflowError: an integer past any float (10**400).
            raise ValueError(
                f"{name} must be a number or an array of numbers ({error})"
            ) from None
    try:
        broadcast = np.broadcast_arrays(*arrays)
    except ValueError:
        shapes = ", ".join(f"{n} {a.shape}" for n, a in zip(names, arrays))
        raise ValueError(f"the shapes do not broadcast together: {shapes}") from None
    shape = broadcast[0].shape
    return [np.ascontiguousarray(a.reshape(-1)) for a in broadcast], shape
