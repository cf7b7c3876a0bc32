"""host.control: the control laws (PID, the float64 network controller, the tanh law, baselines, the generated controller in the loop) and the one controller registry."""
