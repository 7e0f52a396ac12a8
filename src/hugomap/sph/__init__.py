"""Contact SPH (CSPH) solver for solids with strength."""
