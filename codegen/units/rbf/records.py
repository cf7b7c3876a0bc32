"""The rbf unit's records (the C structs of templates/rbf.h.j2 as numpy dtypes, 4-byte fields, no
padding) and status bits; docs/rbf-backstepping.md section 11 defines every field."""
from __future__ import annotations

import numpy as np

V3 = ("<f4", (3,))
INPUT_DTYPE = np.dtype([
    ("los", *V3), ("los_rate", *V3), ("euler", *V3), ("omega", *V3),
    ("los_d", *V3), ("los_d_rate", *V3), ("los_d_acc", *V3),
    ("euler_d", *V3), ("euler_d_rate", *V3), ("euler_d_acc", *V3),
])
OUTPUT_DTYPE = np.dtype([("force", *V3), ("torque", *V3), ("w_hat", "<f4", (6,)), ("status", "<u4")])

# status bits (several may be set; 0 = nominal, nothing limited)
STATUS_OK = 0
STATUS_INVALID_INPUT = 1      # outside the valid box: zero output, weights unchanged, command 0
STATUS_FORCE_LIMITED = 2      # a force component was clipped to +-force_max
STATUS_TORQUE_LIMITED = 4     # a torque component was clipped to +-torque_max
STATUS_WEIGHT_BOUND = 8       # the adaptation clipped a weight to its bound
STATUS_STATE_REPAIRED = 16    # on entry a state word was non-finite (reset to 0) or beyond its bound (clipped)


def state_dtype(nodes: int) -> np.dtype:
    """theta[j*6 + k], theta_delta[j*6 + k]: node j, channel k; command[6]: the last output normalised,
    (force / force_max, torque / torque_max), each in [-1, 1] (the second network's input)."""
    return np.dtype([("theta", "<f4", (nodes * 6,)), ("theta_delta", "<f4", (nodes * 6,)), ("command", "<f4", (6,))])
