"""The shock's profile in the front's frame from a piston checkpoint (``loaded.nc``, or a
piston point's partial checkpoint): what ``hugomap profile`` draws, to show a wave's
structure (an elastic precursor ahead of a plastic front, a relaxation zone behind it).

The checkpoint's history holds the raw per-bin sums of every sample (``hist_sums``, the
backend's ``profile_sums``: bins of ``shock.bin_width`` from x = 0). The last ``samples``
samples are shifted by whole bins so that their fronts coincide with the last one's, summed,
and read in slabs of ``merge`` bins by the backend's own profile reader (``Profile.state``,
the formulas every point is measured with), so a field at a bin is the mean over
``samples`` × ``merge`` bins' atoms.
"""

from __future__ import annotations

import json
import os

import numpy as np

from ..registry import backend as backend_of
from .files import history_of, info_of, is_ok, open_dataset

FIELDS = ("rho", "u", "P", "Pyy", "Pzz", "E", "T")


def front_profile(
    checkpoint: str | os.PathLike, samples: int = 10, merge: int = 2
) -> dict[str, object]:
    """The profile behind and ahead of the front of a piston ``checkpoint``: a dict with
    ``x`` (bin centre minus the front position, the backend's length [σ | m]), the
    ``FIELDS`` as arrays (the backend's units: ρ [σ⁻³ | kg m⁻³], u [σ/τ | m/s], P_xx, P_yy,
    P_zz [ε σ⁻³ | Pa], E [ε | J/kg], T [ε/k_B | K]), ``units`` (the backend's unit names of
    each), ``scene`` (its name), ``t`` (the last sample's time) and ``samples``, ``merge``
    as used. ValueError when the checkpoint has no profile history or failed."""
    if samples < 1 or merge < 1:
        raise ValueError(f"samples = {samples}, merge = {merge}: each must be at least 1")
    ds = open_dataset(checkpoint)
    if not is_ok(ds):
        raise ValueError(f"{checkpoint}: status {ds.attrs.get('status')}: no profile to draw")
    if "hist_sums" not in ds or "scene_config" not in ds.attrs:
        raise ValueError(f"{checkpoint}: no profile history (a piston's loaded.nc has one)")
    scene = json.loads(ds.attrs["scene_config"])
    b = backend_of(scene)
    sim = b.load(ds, checkpoint)
    try:
        profile = b.profile(sim, scene, info_of(ds))
    finally:
        close = getattr(sim, "close", None)
        if close is not None:
            close()
    h = history_of(ds).arrays()
    good = np.flatnonzero(np.isfinite(h["front"]))
    if good.size == 0:
        raise ValueError(f"{checkpoint}: no sample with a front position")
    take = good[-samples:]
    sums = h["sums"][take]
    width, x0 = float(profile.bin_width), float(getattr(profile, "x0", 0.0))
    f_last = float(h["front"][take[-1]])
    nb = sums.shape[1]
    total = np.zeros(sums.shape[1:])
    for s, f in zip(sums, h["front"][take], strict=True):
        k = int(round((f_last - float(f)) / width))  # bins the front moved since
        if k >= 0:
            total[k:] += s[: nb - k] if k else s
        else:
            total[:k] += s[-k:]
    nc = nb // merge
    out: dict[str, list[float]] = {k: [] for k in FIELDS}
    for i in range(nc):
        summed = total[i * merge : (i + 1) * merge].sum(axis=0)
        if summed[0] < 2:  # fewer than two atoms: no state
            for k in FIELDS:
                out[k].append(np.nan)
            continue
        st = profile.state(summed, merge * len(take))
        for k in FIELDS:
            v = getattr(st, k, None)
            out[k].append(np.nan if v is None else float(v))
    x = x0 + (np.arange(nc) + 0.5) * merge * width - f_last
    t = b.units
    units = {"x": t.axes["length"], "u": t.axes["velocity"]}
    units.update({k: t.point[k][0] for k in FIELDS if k not in units})
    return {
        "x": x,
        **{k: np.asarray(v) for k, v in out.items()},
        "units": units,
        "scene": str(scene.get("name", "")),
        "t": float(h["t"][take[-1]]),
        "samples": int(len(take)),
        "merge": int(merge),
    }
