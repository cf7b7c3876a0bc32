"""host.plant: the physical world the controller flies in: orbit, Earth, environment, disturbances, spacecraft with its wheels, the rigid body of paper 000, sensors."""
