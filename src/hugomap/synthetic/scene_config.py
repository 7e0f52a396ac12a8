"""Config of a synthetic scene: its cross-key checks (light: run at validation)."""

from __future__ import annotations


def resolve_defaults(scene: dict) -> None:
    """Every default is a constant of the schema."""


def check(base: str, scene: dict, cfg: dict) -> list[str]:
    """The window must fit in the sample, the bins in the window."""
    out = []
    L, w = scene["sample"]["length"], scene["window"]["length"]
    if w >= L:
        out.append(f"{base}.window.length = {w}: must be shorter than sample.length = {L}")
    if scene["shock"]["bin_width"] * 8 > w:
        out.append(f"{base}.shock.bin_width = {scene['shock']['bin_width']}: at most "
                   f"window.length/8 = {w / 8:.4g}")  # fmt: skip
    return out
