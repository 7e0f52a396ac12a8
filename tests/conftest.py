"""Fixtures shared by every test folder."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

# The files whose tests take the longest, heaviest first. pytest-xdist's loadfile hands a file
# to a worker as one unit, in collection order (with --no-loadscope-reorder; by default it
# puts the files with most tests first, which started these last and left one core idle for
# minutes at the end). Longest first is the classic schedule for two cores. Wall seconds with
# the suite sharing the 2-core machine with a 2-rank MD run (so about twice a quiet run's),
# December 2026: lammps_piston 510, workflow 345, slurm 310, piston_liquid 315, cf_outputs
# 245, aggregate_scale 220, synthetic_backend 165, resume 135, lammps_metal 130,
# sph_piston 105, checkpoint_integrity 100, lammps_shockframe 95, campaign_workflow 90. A
# stale entry costs only scheduling, never a result.
HEAVIEST_FIRST = (
    "lammps/test_lammps_piston.py",
    "workflow/test_workflow.py",
    "physics/test_piston_liquid.py",
    "workflow/test_slurm.py",
    "unit/test_cf_outputs.py",
    "workflow/test_aggregate_scale.py",
    "workflow/test_synthetic_backend.py",
    "workflow/test_resume.py",
    "lammps/test_lammps_metal.py",
    "physics/test_sph_piston.py",
    "unit/test_checkpoint_integrity.py",
    "lammps/test_lammps_shockframe.py",
    "workflow/test_campaign_workflow.py",
    "workflow/test_sph_workflow.py",
    "lammps/test_lammps_sample.py",
)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Collect the heaviest files first (``HEAVIEST_FIRST``), the rest in their own order."""
    rank = {name: i for i, name in enumerate(HEAVIEST_FIRST)}
    here = Path(__file__).parent

    def key(item: pytest.Item) -> int:
        path = item.path
        rel = path.relative_to(here).as_posix() if path.is_relative_to(here) else ""
        return rank.get(rel, len(rank))

    items.sort(key=key)  # stable: a file's tests keep their order


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
