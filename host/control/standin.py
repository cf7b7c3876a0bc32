"""A stand-in network until the trained one exists: a 12-40-3 tansig net fitted to the PID law.

The network input is the paper's S_in = [ω_d, ω̇_d, A_bd, ω_e] in Table 2 units; the target is
the Table 1 PID law with a zero integrator, M = −(Kp·A_bd° + Kd·ω_e°/s), clipped to the wheel
torque limit — so the generated controller has a realistic, stabilising network to carry through
codegen, SIL and PIL before sample creation and training (issue 6) produce the real one. It is
labelled as a stand-in in the artifact's metadata.
"""
from __future__ import annotations

import hashlib

import numpy as np

from codegen import artifact as art
from host.control.pid import TABLE1_GAINS, PidGains
from host.plant.spacecraft import TABLE6

STANDIN_SAMPLES = 4_000
STANDIN_STEPS = 1_000


def pid_targets(x_deg: np.ndarray, gains: PidGains = TABLE1_GAINS, limit: float = TABLE6.torque_limit) -> np.ndarray:
    """The PID torque [N·m] for network inputs in Table 2 units (columns 6-8 A_bd°, 9-11 ω_e°/s)."""
    raw = -(gains.kp * x_deg[:, 6:9] + gains.kd * x_deg[:, 9:12])
    return np.clip(raw, -limit, limit)


def fit_pid_standin(seed: int = 0, n: int = STANDIN_SAMPLES, steps: int = STANDIN_STEPS) -> art.Artifact:
    """Fit the 12-40-3 net to the PID law inside the Table 2 envelope (Adam, full batch, seeded)."""
    import torch

    env = art.table2_envelope()
    rng = np.random.default_rng(seed)
    lo, hi = env.min.astype(np.float64), env.max.astype(np.float64)
    x = lo + (hi - lo) * rng.random((n, lo.size))
    y = pid_targets(x)
    x_min, x_max, y_min, y_max = lo, hi, y.min(axis=0), y.max(axis=0)

    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # a 12-40-3 net: more threads only fight each other (60x slower seen)
    try:
        model = _fit(torch, x, y, x_min, x_max, y_min, y_max, seed, steps)
    finally:
        torch.set_num_threads(threads)
    meta = {"creator": "staregen stand-in (network fitted to the Table 1 PID law, not optimal control)",
            "seed": int(seed), "dataset_sha256": hashlib.sha256(x.tobytes() + y.tobytes()).hexdigest()}
    return art.from_torch(model.float(), x_min, x_max, y_min, y_max, envelope=env, metadata=meta)


def _fit(torch, x, y, x_min, x_max, y_min, y_max, seed: int, steps: int):
    torch.manual_seed(seed)
    model = torch.nn.Sequential(torch.nn.Linear(12, 40), torch.nn.Tanh(), torch.nn.Linear(40, 3)).double()
    xn = torch.from_numpy(2 * (x - x_min) / (x_max - x_min) - 1)
    yn = torch.from_numpy(2 * (y - y_min) / (y_max - y_min) - 1)
    opt = torch.optim.Adam(model.parameters(), lr=1e-2)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, steps)
    for _ in range(steps):
        opt.zero_grad()
        loss = torch.mean((model(xn) - yn) ** 2)
        loss.backward()
        opt.step()
        sched.step()
    return model
