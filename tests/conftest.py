"""Fixtures shared by every test folder."""

from __future__ import annotations

import warnings

import pytest


@pytest.fixture(scope="session")
def cf_errors():
    """``cf_errors(path)``: the errors the IOOS compliance-checker reports for a netCDF file
    against CF-1.11 (its high-priority failures, as ``compliance-checker -t cf:1.11`` lists
    them under "Errors"), plus any check that crashed, as messages; [] for a conformant
    file. Offline: the checker's CF tables ship with it."""
    with warnings.catch_warnings():  # its deprecated IOOS SOS checkers say so on import
        warnings.simplefilter("ignore", DeprecationWarning)
        from compliance_checker.runner import CheckSuite

        suite = CheckSuite()
        suite.load_all_available_checkers()

    def run(path) -> list[str]:
        ds = suite.load_dataset(str(path))
        try:
            groups, crashed = suite.run_all(ds, ["cf:1.11"], skip_checks=[])["cf:1.11"]
        finally:
            ds.close()
        out = [f"check {name} crashed: {err[0]}" for name, err in crashed.items()]

        def walk(results) -> None:
            for r in results:
                got, of = r.value if isinstance(r.value, tuple) else (int(bool(r.value)), 1)
                if r.weight == 3 and got < of:  # BaseCheck.HIGH: the report's "Errors"
                    out.extend(r.msgs or [str(r.name)])
                walk(r.children or [])

        walk(groups)
        return out

    return run
