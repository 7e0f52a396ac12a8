"""What the window stages share: open a window checkpoint, write a window point."""

from __future__ import annotations

import json
import os
from pathlib import Path

from ..failures import StageFailed
from ..io.dataset import average_vars, control_vars, profile_vars
from ..methods.control import ControlHistory, OmegaSignal
from ..methods.steady import mean_profile
from ..states import Pole
from .files import info_of, is_ok, open_dataset, write_point


def open_window(b, path: str | os.PathLike, scene: dict):
    """(window, ω signal, pole, dataset) of a window checkpoint; a failed window stage's
    file raises ``StageFailed`` with its status."""
    ds = open_dataset(path)
    if not is_ok(ds):
        raise StageFailed(ds.attrs["status"], ds.attrs.get("diagnostic", ""))
    win = b.load_window(ds, path)
    profile = b.profile(win, scene, info_of(ds))
    sig = OmegaSignal(**json.loads(ds.attrs["omega_signal"]), profile=profile)
    return win, sig, Pole.from_dict(json.loads(ds.attrs["pole"])), ds, profile


def window_point(
    out: str | os.PathLike, b, scheme: str, scene: dict, u_p: float, pole: Pole | None,
    win, values: dict, cost: dict, status: str, diagnostic: str, h: dict | None = None,
    profile=None, control: ControlHistory | None = None, extra: dict | None = None,
) -> Path:  # fmt: skip
    """Write a window point: ``values`` with ``cost`` (wall_s, cpu_s [s], atom_steps of this
    job and of the jobs it needed: loading, window set-up, trials), the steady profile of
    the samples ``h``, the control record and ``extra`` variables."""
    values = {**values, **cost, "piston_velocity": u_p}
    more = dict(extra or {})
    if h is not None and profile is not None:
        more.update(profile_vars(mean_profile(h, profile), b.units))
        more.update(average_vars(h, b.units))
    if control is not None and control.t:
        more.update(control_vars(control, b.units))
    hist = (
        None
        if h is None
        else {k: h[k] for k in ("t", "front", "stage", "omega", "u_slab", "P_slab") if k in h}
    )
    attrs = {} if win is None else {"u_in": win.u_in, "u_out": win.u_out,
                                    "window_length": win.geom.length}  # fmt: skip
    return write_point(out, b, scene, scheme, values, {} if pole is None else pole.as_dict(),
                       hist, status, diagnostic, more, attrs)  # fmt: skip


def failed_point(out, b, scheme: str, scene: dict, u_p: float, clock, status: str,
                 diagnostic: str) -> Path:  # fmt: skip
    """A window point that has no window to run: its status and this job's cost."""
    return window_point(out, b, scheme, scene, u_p, None, None, {}, clock.cost(), status,
                        diagnostic)  # fmt: skip


def prior_cost(ds) -> dict:
    """The cost carried by a window checkpoint (loading and window set-up)."""
    return json.loads(ds.attrs.get("cost", "{}"))


__all__ = ["failed_point", "open_window", "prior_cost", "window_point"]
