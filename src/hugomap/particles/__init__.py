"""What the two particle backends share: numba MD (``hugomap.md``) and LAMMPS
(``hugomap.lammps``) stand side by side on this package, and it imports neither.

- ``fcc``: an FCC lattice and Maxwell velocities (a sample's, a reservoir's first state);
- ``sizing``: the equilibration between walls that sizes a sample's box (``size_bulk``);
- ``bins``: the per-bin sums (``bin_sums``, the one binning kernel); ``profiles``: the fields made
  of them and the profile reader (``ParticleProfile``);
- ``pole``: the pole measured on a prepared sample (``measure_pole``) and the pole a
  reference is computed at (``reference_pole``);
- ``kit``: what the window and the reservoir need of a backend (``ParticleKit``);
- ``window``: the moving window over any particle simulation (``ParticleWindow``);
- ``reservoir``: the window's inflow snapshot and its screen (``make_reservoir``);
- ``snapshot``: the frame of a snapshot's velocities (``velocity_frame``).

Everything is in the simulation's own units (reduced LJ units, or LAMMPS's).
"""
