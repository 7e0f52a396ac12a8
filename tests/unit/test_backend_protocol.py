"""Every registered backend against the ``Backend`` protocol (hugomap.backend), so that a
backend which drifts from the protocol fails here rather than in a stage.

References: the protocol class itself, read with ``inspect``: its methods (every public
function it defines) and attributes (its annotations), less ``OPTIONAL_MEMBERS``, which a
backend may lack but, if it has one, must match too. A backend's method is compatible with
the protocol's when a stage can call it as the protocol says: the protocol's parameters
(``self`` aside) are the backend's first parameters, by name and in order (so positional
and keyword calls both work); a parameter the protocol gives a default has one in the
backend; any further parameter of the backend has a default. An attribute exists and has
the annotated type. The documented ``reference_from_sample`` contract: such a backend's
``reference`` and ``reference_inputs`` also take the sample's ``pole`` second.

The backends are the registry's (``registry.backend`` per solver), and for ``lammps`` both
unit systems' (``for_scene``: units lj and metal). Importing the LAMMPS backend must not load
LAMMPS: a fresh interpreter with ``import lammps`` made to fail gets both of them from the
registry.
"""

from __future__ import annotations

import inspect
import os
import subprocess
import sys
import typing
from pathlib import Path

import pytest

from hugomap import registry
from hugomap.backend import OPTIONAL_MEMBERS, Backend

ROOT = Path(__file__).resolve().parents[2]
#: scenes that pick each of a solver's backends (``for_scene``); others: one, from {}
SCENES = {"lammps": {"lj": {"model": {"units": "lj"}}, "metal": {"model": {"units": "metal"}}}}
CASES = [(solver, label, scene) for solver in registry.REGISTRY
         for label, scene in SCENES.get(solver, {"": {}}).items()]  # fmt: skip
P = inspect.Parameter


def protocol_methods() -> dict[str, typing.Callable]:
    """The protocol's methods: every public function its class defines."""
    return {n: f for n, f in vars(Backend).items()
            if inspect.isfunction(f) and not n.startswith("_")}  # fmt: skip


def protocol_attributes() -> dict[str, type]:
    """The protocol's attributes and their types (its annotations, resolved)."""
    return typing.get_type_hints(Backend)


def incompatibility(proto: typing.Callable, impl: typing.Callable) -> str | None:
    """Why ``impl`` (a bound method) cannot be called as the protocol's ``proto`` says (the
    rule of the module docstring); None when it can."""
    want = list(inspect.signature(proto).parameters.values())[1:]  # self aside
    have = list(inspect.signature(impl).parameters.values())
    lead = [p for p in have if p.kind in (P.POSITIONAL_ONLY, P.POSITIONAL_OR_KEYWORD)]
    lead = lead[: len(want)]
    if [p.name for p in lead] != [p.name for p in want] or any(
        p.kind is P.POSITIONAL_ONLY for p in lead
    ):
        return f"parameters {[p.name for p in have]}, protocol {[p.name for p in want]}"
    for w, h in zip(want, lead, strict=True):
        if w.default is not P.empty and h.default is P.empty:
            return f"{h.name!r} needs a default (the protocol's callers may omit it)"
    extra = [p.name for p in have if p not in lead and p.default is P.empty
             and p.kind not in (P.VAR_POSITIONAL, P.VAR_KEYWORD)]  # fmt: skip
    if extra:
        return f"required parameters {extra} that the protocol does not pass"
    return None


def problems(backend: object) -> list[str]:
    """What ``backend`` lacks or gets wrong of the protocol."""
    out = []
    for name, kind in protocol_attributes().items():
        if not hasattr(backend, name):
            out.append(f"attribute {name!r} missing")
        elif not isinstance(getattr(backend, name), kind):
            out.append(f"attribute {name!r} is {type(getattr(backend, name)).__name__}, "
                       f"not {kind.__name__}")  # fmt: skip
    for name, proto in protocol_methods().items():
        impl = getattr(backend, name, None)
        if impl is None:
            if name not in OPTIONAL_MEMBERS:
                out.append(f"method {name!r} missing")
            continue
        if not callable(impl):
            out.append(f"{name!r} is not callable")
            continue
        why = incompatibility(proto, impl)
        if why:
            out.append(f"{name}: {why}")
    return out


def test_the_protocol_declares_members():
    methods, attributes = protocol_methods(), protocol_attributes()
    assert {"prepare", "save", "load", "open_window", "reference", "cost"} <= set(methods)
    assert set(attributes) == {"name", "units"}
    assert OPTIONAL_MEMBERS <= set(methods) | set(attributes)


@pytest.mark.parametrize(("solver", "label", "scene"), CASES,
                         ids=[f"{s}-{u}" if u else s for s, u, _ in CASES])  # fmt: skip
def test_registered_backend_follows_the_protocol(solver, label, scene):
    backend = registry.backend({"solver": solver, **scene})
    assert problems(backend) == []
    assert backend.name == solver  # the stages name the solver by it
    if getattr(backend, "reference_from_sample", False):
        for name in ("reference", "reference_inputs"):
            inspect.signature(getattr(backend, name)).bind({}, None)  # (scene, pole)


def test_a_drifted_backend_is_caught():
    """The check itself: a backend with a renamed, an added required and a missing
    parameter, a missing method and a wrong attribute fails, naming each."""
    base = registry.backend({"solver": "synthetic"})

    class Drifted:
        name = "drifted"
        units = "SI"

        def __getattr__(self, attr):
            return getattr(base, attr)

        def load(self, dataset, source=None):  # renamed ds
            raise NotImplementedError

        def start_piston(self, solver, scene, u_p, extra):  # one more, required
            raise NotImplementedError

        def cost(self, scene):  # stage missing
            raise NotImplementedError

        def figure_labels(self, scene, info):  # the protocol passes no info
            raise NotImplementedError

        def read_checkpoint(self, path, /):  # positional only: path= fails
            raise NotImplementedError

        load_window = None  # missing

    found = "\n".join(problems(Drifted()))
    for words in ("attribute 'units' is str", "load: parameters", "start_piston: required",
                  "cost: parameters", "figure_labels: required", "read_checkpoint: parameters",
                  "method 'load_window' missing"):  # fmt: skip
        assert words in found, (words, found)
    assert "shock_frame_point" not in found  # optional: the synthetic backend lacks it


SCRIPT = """
import sys
sys.modules["lammps"] = None  # from here on ``import lammps`` raises ImportError
from hugomap import registry
for units in ("lj", "metal"):
    b = registry.backend({"solver": "lammps", "model": {"units": units}})
    print(units, type(b).__name__, b.name)
print("lammps module:", sys.modules["lammps"])
"""


def test_lammps_backend_imports_without_lammps():
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    r = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                       env=env, cwd=ROOT, timeout=300)  # fmt: skip
    assert r.returncode == 0, r.stderr[-3000:]
    assert r.stdout.split("\n")[:3] == [
        "lj LammpsBackend lammps",
        "metal MetalBackend lammps",
        "lammps module: None",
    ]
