"""Tuning and evaluation of the controllers (paper 001 §7): the Table 7 PID grid on the batched simulator."""
