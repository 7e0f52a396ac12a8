"""The workflow's stages, one file a stage: file in, file out, no physics of their own.

Every stage is solver-agnostic: it asks the registry for the scene's backend
(``hugomap.registry``) and drives it through the ``Backend`` protocol and the methods of
``hugomap.methods``. A stage whose solver breaks still writes its output, marked with a
``status`` and a ``diagnostic``, so the aggregate keeps the point, marked failed.

    prepare_sample ─▶ load_to_target ─┬─ piston_point
                                      └─ window_start ─┬─ control_point (AMW, MW)
                                                       └─ dichotomy_state ⇄ dichotomy_trial
                                                          ─▶ dichotomy_point
    prepare_sample ─▶ shock_frame_point (msst, nphug: solver lammps)
    reference_stage; aggregate
"""

import importlib

# Each stage by the module it lives in; ``hugomap.stages.<name>`` resolves lazily (PEP 562),
# so that importing one stage module does not import the others through this package.
_STAGES = {
    "aggregate": "aggregation", "control_point": "control", "dichotomy_point": "dichotomy",
    "dichotomy_state": "dichotomy", "dichotomy_trial": "dichotomy", "load_to_target": "load",
    "piston_point": "piston", "prepare_sample": "sample", "reference_stage": "reference",
    "shock_frame_point": "shockframe", "window_start": "window_cut",
}  # fmt: skip
__all__ = sorted(_STAGES)


def __getattr__(name: str):
    if name in _STAGES:
        return getattr(importlib.import_module(f"{__name__}.{_STAGES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
