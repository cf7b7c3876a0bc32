"""A small GP artifact and law made with numpy alone (no training): the unit's example inputs for the
tests written once for every unit, deterministic in its seed. Not a trained model: inducing points
and variational parameters are drawn at random in the normalised space, so every code path of the
step (inside the data, far from it, the clamps) is reachable with a few points."""
from __future__ import annotations

import numpy as np

from codegen.units.gp import artifact as gpa
from codegen.units.gp.params import GpLawParams

# Table 6's inertia (paper 001; host/plant/spacecraft.TABLE6_INERTIA, written out because codegen
# must not import host; tests/codegen/units/gp checks the two agree)
TABLE6_INERTIA = ((797.34, -14.3, -25.1), (-14.3, 304.86, -10.5), (-25.1, -10.5, 792.48))


def example_arrays(m: int = 8, seed: int = 0) -> gpa.GpArrays:
    rng = np.random.default_rng(seed)
    R = np.tril(rng.normal(0.0, 0.05, (3, m, m)), -1)
    for k in range(3):
        R[k][np.diag_indices(m)] = rng.uniform(0.05, 0.6, m)
    R[2, 0, 0] = 1.3          # one axis with an S eigenvalue above 1: reaches the variance ceiling
    Z = rng.normal(0.0, 0.15, (m, gpa.N_IN))
    Z[:, 6:] = 0.0            # omega_dot = 0 at the inducing points: the flight inputs can sit on them
    return gpa.GpArrays(
        input_scale=np.array(gpa.INPUT_SCALES, dtype=np.float64),
        output_scale=np.array([0.03, 0.05, 0.04]),
        lengthscale=rng.uniform(0.3, 0.8, gpa.N_IN),
        outputscale=float(rng.uniform(0.5, 1.5)),
        noise=np.array([1e-3, 2e-3, 1.5e-3]),
        jitter=0.0,       # no jitter: the Nystrom residual at an inducing point is 0, so rounding reaches the floor
        Z=Z,
        m=rng.normal(0.0, 0.8, (3, m)),
        R=R,
    )


def example_artifact(m: int = 8, seed: int = 0) -> gpa.GpArtifact:
    a = example_arrays(m, seed)
    raw = a.Z * a.input_scale
    return gpa.GpArtifact(arrays=a, envelope_min=raw.min(0), envelope_max=raw.max(0),
                          metadata={"creator": "codegen.units.gp.example (random, untrained)", "seed": seed})


def example_params(m: int = 8, seed: int = 0) -> GpLawParams:
    return GpLawParams(gp=example_artifact(m, seed), inertia=TABLE6_INERTIA, artifact_name="example.json")
