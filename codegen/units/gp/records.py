"""The gp unit's records (the C structs of templates/gp.h.j2 as numpy dtypes, 4-byte fields, no
padding), status bits and valid box; docs/gp-takeover.md section 11 defines every field."""
from __future__ import annotations

import numpy as np

V3 = ("<f4", (3,))
INPUT_DTYPE = np.dtype([("q", "<f4", (4,)), ("omega", *V3), ("h_w", *V3)])
OUTPUT_DTYPE = np.dtype([("torque", *V3), ("mu", *V3), ("var", *V3), ("gains", "<f4", (2,)), ("status", "<u4")])

# status bits (several may be set; 0 = nominal, nothing clamped)
STATUS_OK = 0
STATUS_INVALID_INPUT = 1      # outside the valid box: zero torque and mean, prior variance, upper gains
STATUS_TORQUE_LIMITED = 2     # a torque component was clipped to +-torque_max
STATUS_VAR_FLOOR = 4          # the Nystrom residual k_xx - |w|^2 rounded below 0 (or NaN): set to 0
STATUS_VAR_CEILING = 8        # a variance exceeded the prior k_xx (an S eigenvalue > 1, or rounding): clamped

# the valid box (SI units): outside it the step refuses (docs/gp-takeover.md section 11, step 0)
Q_MAX = 1.1                   # |q_i|
NORM2_MIN, NORM2_MAX = 0.81, 1.21   # |q|^2 (|q| within 10 % of 1)
RATE_MAX = 0.2                # rad/s, |omega_i|
MOMENTUM_MAX = 100.0          # N*m*s, |h_w,i| (twice the wheels' 50 N*m*s)
EXPONENT_MIN = -87.0          # the kernel exponent's floor: e^t stays a normal float32
