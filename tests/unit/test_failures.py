"""The failure exceptions and the checkpoint module: what each ``except`` catches, CSPH
checkpoints refused like MD ones (``CheckpointError`` naming the file), and the bottom layer
(``failures``, ``io.checkpoint``) importing nothing above it."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from hugomap.eos import copper
from hugomap.failures import (
    FAILURES,
    CheckpointError,
    HugomapFailure,
    SlabError,
    SolverUnstable,
    SPHUnstable,
    StageFailed,
    WindowError,
)
from hugomap.io.checkpoint import (
    CSPH_CHECKPOINT,
    CSPH_WINDOW_CHECKPOINT,
    MD_CHECKPOINT,
    MD_WINDOW_CHECKPOINT,
    verify_checkpoint,
)
from hugomap.sph import checkpoint as ckpt
from hugomap.sph.simulation import CSPHSimulation
from hugomap.sph.state import SPHState

SRC = Path(__file__).resolve().parents[2] / "src" / "hugomap"


@pytest.mark.parametrize("cls", [SolverUnstable, SPHUnstable, StageFailed, WindowError, SlabError])
def test_status_exceptions_carry_status_and_diagnostic(cls):
    exc = cls("nan", "at step 3")
    assert isinstance(exc, HugomapFailure) and isinstance(exc, RuntimeError)
    assert (exc.status, exc.diagnostic, str(exc)) == ("nan", "at step 3", "nan: at step 3")
    assert not isinstance(exc, ValueError)


def test_except_clauses_catch_what_they_did():
    with pytest.raises(SolverUnstable):  # the MD handlers also catch the CSPH solver's
        raise SPHUnstable("eos_range", "x")
    err = CheckpointError("a.nc", "checksum mismatch")
    assert isinstance(err, ValueError) and not isinstance(err, HugomapFailure)
    assert (err.source, err.problem) == ("a.nc", "checksum mismatch")
    assert str(err) == "refused checkpoint a.nc: checksum mismatch"
    assert {"nan", "cfl", "too_few_samples", "no_inflow"} <= set(FAILURES)


def test_checkpoint_kinds_keep_their_format_strings():
    assert MD_CHECKPOINT.format == "hugomap-md-checkpoint/2"
    assert MD_WINDOW_CHECKPOINT.chain() == (MD_CHECKPOINT, MD_WINDOW_CHECKPOINT)
    assert MD_WINDOW_CHECKPOINT.format == "hugomap-md-window/2"
    assert CSPH_CHECKPOINT.format == "hugomap-sph-checkpoint/1"
    assert CSPH_WINDOW_CHECKPOINT.format == "hugomap-sph-window/2"


def _csph() -> CSPHSimulation:
    n, dx = 20, 1e-5
    st = SPHState(x=(np.arange(n) + 0.5) * dx, v=np.zeros(n), m=8930.0 * dx, rho=8930.0, e=0.0)
    sim = CSPHSimulation(st, copper(), walls=(0.0, 300.0, None, 0.0))
    sim.advance(2)
    return sim


def test_csph_checkpoint_refusals_name_the_file(tmp_path):
    path = ckpt.save_simulation(_csph(), tmp_path / "c.nc")
    ds = ckpt.load_simulation(path)[1]
    verify_checkpoint(ds, path, CSPH_CHECKPOINT)
    with pytest.raises(CheckpointError, match="not an MD checkpoint"):
        verify_checkpoint(ds, path)  # a CSPH checkpoint is not an MD one
    truncated = tmp_path / "truncated.nc"
    truncated.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(CheckpointError) as info:
        ckpt.load_simulation(truncated)
    assert str(truncated) in str(info.value)
    ds.attrs["sim_format"] = "hugomap-sph-checkpoint/0"
    with pytest.raises(CheckpointError, match=r"mem: not a CSPH checkpoint \(sim_format"):
        ckpt.from_dataset(ds, "mem")


def _hugomap_imports(path: Path) -> set[str]:
    """The hugomap modules ``path`` imports (relative imports resolved)."""
    package = ".".join(("hugomap", *path.relative_to(SRC).parent.parts))
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                out.add(f"{base}.{node.module}" if node.module else base)
            elif (node.module or "").startswith("hugomap"):
                out.add(node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.startswith("hugomap"))
    return out


def test_bottom_layer_imports_nothing_above_it():
    assert _hugomap_imports(SRC / "failures.py") == set()
    assert _hugomap_imports(SRC / "io" / "checkpoint.py") == {"hugomap.failures"}
