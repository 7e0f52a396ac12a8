"""No strength (hydrodynamic material): G = 0, the deviatoric stress stays zero.

Params layout (shared with ``von_mises`` so the kernels take one array): [G = 0, Y = 0].
"""

from __future__ import annotations

import numpy as np

PARAMS = np.array([0.0, 0.0])
