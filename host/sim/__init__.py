"""host.sim: closed-loop simulation, metrics, targets, campaigns, impulse, plots, the paper-000 example and the realistic inputs the host hands to the generated units."""
