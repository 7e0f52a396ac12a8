"""The workflow's stages, one file a stage: file in, file out, no physics of their own.

Every stage is solver-agnostic: it asks the registry for the scene's backend
(``hugomap.registry``) and drives it through the ``Backend`` protocol and the methods of
``hugomap.window``. A stage whose solver breaks still writes its output, marked with a
``status`` and a ``diagnostic``, so the aggregate keeps the point, marked failed.

    prepare_sample ─▶ load_to_target ─┬─ piston_point
                                      └─ window_start ─┬─ control_point (AMW, MW)
                                                       └─ dichotomy_state ⇄ dichotomy_trial
                                                          ─▶ dichotomy_point
    reference_stage; aggregate
"""

from .aggregate import aggregate
from .control import control_point
from .dichotomy import dichotomy_point, dichotomy_state, dichotomy_trial
from .load import load_to_target
from .piston import piston_point
from .reference import reference_stage
from .sample import prepare_sample
from .window import window_start

__all__ = [
    "aggregate", "control_point", "dichotomy_point", "dichotomy_state", "dichotomy_trial",
    "load_to_target", "piston_point", "prepare_sample", "reference_stage", "window_start",
]  # fmt: skip
