"""hugomap: shock Hugoniots from molecular dynamics and contact SPH in moving windows."""

__version__ = "0.1.0"
