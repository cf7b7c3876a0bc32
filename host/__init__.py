"""Ground-side float64 models: scenario, dynamics, guidance, simulator, controllers, CLI."""
