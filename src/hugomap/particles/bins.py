"""The one binning kernel of the particle backends: per-bin sums of ``profiles.SUM_FIELDS``
over slabs of width w along x (the formulas that turn them into fields:
``profiles.fields_from_sums``)."""

from __future__ import annotations

import numpy as np

from ..numba_conf import njit


@njit
def bin_sums(
    x: np.ndarray, v: np.ndarray, pe: np.ndarray, vir: np.ndarray, width: float, out: np.ndarray
) -> None:
    """Accumulate (+=) the raw per-bin sums of ``SUM_FIELDS`` into ``out`` (nbins, 11)."""
    nbins = out.shape[0]
    for i in range(x.shape[0]):
        b = int(x[i, 0] / width)
        if b < 0 or b >= nbins:
            continue
        out[b, 0] += 1.0
        out[b, 1] += v[i, 0]
        out[b, 2] += v[i, 1]
        out[b, 3] += v[i, 2]
        out[b, 4] += v[i, 0] * v[i, 0]
        out[b, 5] += v[i, 1] * v[i, 1]
        out[b, 6] += v[i, 2] * v[i, 2]
        out[b, 7] += pe[i]
        out[b, 8] += vir[i, 0]
        out[b, 9] += vir[i, 1]
        out[b, 10] += vir[i, 2]
