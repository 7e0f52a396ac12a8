"""hugomap: shock Hugoniots from molecular dynamics and contact SPH in moving windows."""

# Importing hugomap changes nothing of the process (no environment variables): where numba
# caches hugomap's kernels is set for those kernels alone (``numba_conf.HugomapCacheLocator``).

__version__ = "0.1.0"
