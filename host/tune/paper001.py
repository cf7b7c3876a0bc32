"""The published numbers of paper 001 (Li, Dong, Li 2020) that this project compares against:
Tables 8-9 (staring, J_A [°], J_ω [°/s], J̄ with k1 = 1, k2 = 5) and Tables 10-11 (step response,
per axis x, y, z). Table 10's z steady-state error is printed 2.95e-4, but its "average of three
axes" 1.24e-5 is the mean of x, y and 2.95e-5: a misprint, we use 2.95e-5.
"""
from __future__ import annotations

TABLE8 = {"PID": (3.96e-4, 4.23e-5, 6.07e-4), "NN": (2.13e-4, 3.81e-5, 4.03e-4)}   # central target
TABLE9 = {"PID": (3.96e-4, 4.25e-5, 6.09e-4), "NN": (2.13e-4, 3.76e-5, 4.01e-4)}   # 100 targets
STEP = {   # Tables 10 (PID) and 11 (NN): overshoot %, settling s, steady-state error (deg), per axis
    "PID": {"overshoot_pct": (13.49, 0.97, 1.12), "settling_s": (10.33, 3.67, 8.06),
            "steady_state_deg": (7.34e-6, 4.19e-7, 2.95e-5)},
    "NN": {"overshoot_pct": (2.80, 0.001, 3.56), "settling_s": (3.07, 3.42, 2.99),
           "steady_state_deg": (7.13e-6, 5.38e-8, 1.33e-5)},
}
NN_TO_PID_RATIO = TABLE9["NN"][2] / TABLE9["PID"][2]    # 0.658: the network's J̄ over the PID's
