"""Fixtures shared by the MD unit tests."""

from __future__ import annotations

import pytest

from ._reference import one_numba_thread


@pytest.fixture
def serial_numba():
    """Run numba's parallel kernels on one thread for this test (see one_numba_thread)."""
    with one_numba_thread():
        yield
