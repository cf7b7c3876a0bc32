"""Golden model of templates/satlin.c.j2: u_i = clip(sum_j K_ij x_j, -L, L), summed in index order
from 0, NaN -> 0 (the C's comparisons), float32 throughout."""
import numpy as np

F32 = np.float32


def step(K: np.ndarray, limit: np.float32, x: np.ndarray) -> np.ndarray:
    """x (N, 3) float32 -> u (N, 3) float32."""
    if x.dtype != F32:
        raise ValueError(f"golden satlin: expected float32, got {x.dtype}")
    u = np.empty_like(x)
    with np.errstate(all="ignore"):
        for i in range(3):
            acc = np.zeros(x.shape[0], F32)
            for j in range(3):
                acc = acc + K[i, j] * x[:, j]
            u[:, i] = np.where(acc > limit, limit, np.where(acc < -limit, -limit, np.where(acc == acc, acc, F32(0))))
    return u
