"""Ground side, float64, by concern: core conventions, plant, guidance (gnc), control laws, simulation (sim),
learning (learn) and the staregen CLI."""
