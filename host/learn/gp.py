"""Ground learning of paper 004's GP attitude-takeover law (issue 27; docs/gp-takeover.md §2-4, §6-7).

Works on data arrays: x (N×9: q_v, ω rad/s, ω̇ rad/s², raw units) and d (N×3, N·m).

- `normalise`: the fixed input scales of §3 (q_v / 0.2, ω / 0.01, ω̇ / 5e-4) and per-axis output
  scales s_y = RMS of d over the training data (no centring).
- `train_exact`: a batch of three independent exact GPs (ZeroMean, ScaleKernel(RBF ARD 9) per axis,
  per-axis noise), ExactMarginalLogLikelihood, Adam lr 0.05, 200 iterations, Cholesky forced at every
  N (`linear_operator.settings.max_cholesky_size`, default 800, set to 10,000; gpytorch.settings
  re-exports the same object).
- `train_sparse`: SVGP with shared inducing points Z (M×9, k-means++ initialised, learned) and one
  shared (un-batched) SE-ARD kernel, a batch of three whitened Cholesky variational distributions via
  GPyTorch's `IndependentMultitaskVariationalStrategy`, per-axis noise (MultitaskGaussianLikelihood,
  rank 0); VariationalELBO, full batch, Adam lr 0.02, 1,000 iterations. GPyTorch broadcasts the
  un-batched Z and kernel over the batch of three (checked by the reference-predictor test).
- Timing (§4): model + likelihood construction and the optimisation loop only, one torch thread,
  float64; k-means timed separately.
- `flight_arrays`, `artifact_from`: the float64 arrays of §6 and the sealed artifact of §7.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import gpytorch
import numpy as np
import torch
from scipy.cluster.vq import kmeans2

from codegen.units.gp import artifact as gpa

INPUT_SCALES = np.array(gpa.INPUT_SCALES, dtype=np.float64)
EXACT_ITERATIONS = 200
EXACT_LR = 0.05
SPARSE_ITERATIONS = 1000
SPARSE_LR = 0.02
DEFAULT_M = 20
MAX_CHOLESKY_SIZE = 10_000
INIT_NOISE = 0.01


def _torch():
    torch.set_num_threads(1)
    return torch


def check_data(x, d) -> tuple[np.ndarray, np.ndarray]:
    x = np.asarray(x, dtype=np.float64)
    d = np.asarray(d, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 9 or d.shape != (x.shape[0], 3):
        raise ValueError(f"expected x (N×9) and d (N×3), got {x.shape} and {d.shape}")
    if not (np.isfinite(x).all() and np.isfinite(d).all()):
        raise ValueError("x and d must be finite")
    return x, d


def output_scales(d: np.ndarray) -> np.ndarray:
    """s_y,k = RMS of d_k over the training data (§3); a zero column gets 1."""
    s = np.sqrt(np.mean(np.asarray(d, dtype=np.float64) ** 2, axis=0))
    return np.where(s > 0, s, 1.0)


def normalise_x(x: np.ndarray) -> np.ndarray:
    return np.asarray(x, dtype=np.float64) / INPUT_SCALES


def mse(pred: np.ndarray, d: np.ndarray) -> dict:
    """§3: mean over samples and axes of (μ − d)² in (N·m)², per axis, and normalised (÷ var d_k)."""
    err = (np.asarray(pred) - np.asarray(d)) ** 2
    per_axis = err.mean(axis=0)
    var = np.var(d, axis=0)
    return {"mse": float(err.mean()), "per_axis": per_axis.tolist(),
            "normalised": (per_axis / np.where(var > 0, var, 1.0)).tolist()}


# ----------------------------------------------------------------------------- models

def _exact_model_class():
    class BatchExactGP(gpytorch.models.ExactGP):
        def __init__(self, tx, ty, likelihood):
            super().__init__(tx, ty, likelihood)
            b = tx.shape[:-2]
            self.mean_module = gpytorch.means.ZeroMean(batch_shape=b)
            self.covar_module = gpytorch.kernels.ScaleKernel(
                gpytorch.kernels.RBFKernel(ard_num_dims=9, batch_shape=b), batch_shape=b)

        def forward(self, x):
            return gpytorch.distributions.MultivariateNormal(self.mean_module(x), self.covar_module(x))

    return BatchExactGP


def _sparse_model_class():
    class SharedSVGP(gpytorch.models.ApproximateGP):
        def __init__(self, Z):
            vd = gpytorch.variational.CholeskyVariationalDistribution(Z.shape[0], batch_shape=(3,))
            vs = gpytorch.variational.IndependentMultitaskVariationalStrategy(
                gpytorch.variational.VariationalStrategy(self, Z, vd, learn_inducing_locations=True),
                num_tasks=3)
            super().__init__(vs)
            self.mean_module = gpytorch.means.ZeroMean()
            self.covar_module = gpytorch.kernels.ScaleKernel(gpytorch.kernels.RBFKernel(ard_num_dims=9))

        def forward(self, x):
            return gpytorch.distributions.MultivariateNormal(self.mean_module(x), self.covar_module(x))

    return SharedSVGP


def _init_kernel(scale_kernel) -> None:
    scale_kernel.outputscale = scale_kernel.outputscale * 0 + 1.0
    scale_kernel.base_kernel.lengthscale = scale_kernel.base_kernel.lengthscale * 0 + 1.0


@dataclass
class GpFit:
    kind: str                    # "exact" or "sparse"
    model: object
    likelihood: object
    output_scale: np.ndarray
    train_time_s: float
    kmeans_time_s: float = 0.0
    n_train: int = 0
    x_min: np.ndarray = field(default_factory=lambda: np.zeros(9))
    x_max: np.ndarray = field(default_factory=lambda: np.zeros(9))
    losses: list = field(default_factory=list)
    seed: int = 0

    def predict(self, x, noise: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Latent mean and variance (N×3 each) in raw units; noise=True adds the per-axis noise."""
        torch = _torch()
        xn = torch.as_tensor(normalise_x(np.atleast_2d(x)), dtype=torch.float64)
        self.model.eval()
        self.likelihood.eval()
        with torch.no_grad(), gpytorch.settings.max_cholesky_size(MAX_CHOLESKY_SIZE), \
                gpytorch.settings.fast_pred_var(False), gpytorch.settings.skip_posterior_variances(False):
            if self.kind == "exact":
                f = self.model(xn.unsqueeze(0).expand(3, *xn.shape))
                mean, var = f.mean.T, f.variance.T                       # (3, N) -> (N, 3)
                if noise:
                    var = var + self.likelihood.noise.reshape(1, 3)
            else:
                f = self.model(xn)
                mean, var = f.mean, f.variance                           # (N, 3)
                if noise:
                    var = var + self.likelihood.task_noises.reshape(1, 3)
        s = self.output_scale
        return mean.numpy() * s, var.numpy() * s ** 2


def train_exact(x, d, iterations: int = EXACT_ITERATIONS, lr: float = EXACT_LR, seed: int = 0) -> GpFit:
    """Batch of three exact GPs on the normalised data (§2, §4); time = construction + Adam loop."""
    torch = _torch()
    x, d = check_data(x, d)
    s = output_scales(d)
    tx = torch.as_tensor(normalise_x(x), dtype=torch.float64)
    ty = torch.as_tensor((d / s).T.copy(), dtype=torch.float64)         # (3, N)
    losses = []
    with torch.random.fork_rng(devices=[]), gpytorch.settings.max_cholesky_size(MAX_CHOLESKY_SIZE):
        torch.manual_seed(seed)
        t0 = time.perf_counter()
        txb = tx.unsqueeze(0).expand(3, *tx.shape)
        likelihood = gpytorch.likelihoods.GaussianLikelihood(batch_shape=torch.Size([3])).double()
        model = _exact_model_class()(txb, ty, likelihood).double()
        _init_kernel(model.covar_module)
        likelihood.noise = torch.full((3, 1), INIT_NOISE, dtype=torch.float64)
        model.train()
        likelihood.train()
        opt = torch.optim.Adam(model.parameters(), lr=lr)      # includes the likelihood's noise
        mll = gpytorch.mlls.ExactMarginalLogLikelihood(likelihood, model)
        for _ in range(iterations):
            opt.zero_grad()
            loss = -mll(model(txb), ty).sum()
            loss.backward()
            opt.step()
            losses.append(loss.item())
        t = time.perf_counter() - t0
    return GpFit("exact", model, likelihood, s, t, 0.0, len(x), x.min(0), x.max(0), losses, seed)


def kmeans_init(xn: np.ndarray, m: int) -> np.ndarray:
    """k-means++ centres of the normalised inputs (scipy kmeans2, minit="++", seed=0)."""
    centres, _ = kmeans2(xn, m, minit="++", seed=0)
    return centres


def train_sparse(x, d, m: int = DEFAULT_M, iterations: int = SPARSE_ITERATIONS, lr: float = SPARSE_LR,
                 seed: int = 0) -> GpFit:
    """SVGP with shared Z and kernel, per-axis q(u) and noise (§2, §4), full-batch ELBO."""
    torch = _torch()
    x, d = check_data(x, d)
    if not 1 <= m <= min(len(x), gpa.MAX_INDUCING):
        raise ValueError(f"m must be in [1, min(N, {gpa.MAX_INDUCING})], got {m}")
    s = output_scales(d)
    xn = normalise_x(x)
    t0 = time.perf_counter()
    Z0 = kmeans_init(xn, m)
    t_km = time.perf_counter() - t0
    tx = torch.as_tensor(xn, dtype=torch.float64)
    ty = torch.as_tensor(d / s, dtype=torch.float64)                     # (N, 3)
    losses = []
    with torch.random.fork_rng(devices=[]):
        torch.manual_seed(seed)
        t0 = time.perf_counter()
        model = _sparse_model_class()(torch.as_tensor(Z0, dtype=torch.float64)).double()
        likelihood = gpytorch.likelihoods.MultitaskGaussianLikelihood(   # per-axis noise only (§2)
            num_tasks=3, rank=0, has_global_noise=False).double()
        _init_kernel(model.covar_module)
        likelihood.task_noises = torch.full((3,), INIT_NOISE, dtype=torch.float64)
        model.train()
        likelihood.train()
        opt = torch.optim.Adam([{"params": model.parameters()}, {"params": likelihood.parameters()}], lr=lr)
        elbo = gpytorch.mlls.VariationalELBO(likelihood, model, num_data=len(x))
        for _ in range(iterations):
            opt.zero_grad()
            loss = -elbo(model(tx), ty)
            loss.backward()
            opt.step()
            losses.append(loss.item())
        t = time.perf_counter() - t0
    return GpFit("sparse", model, likelihood, s, t, t_km, len(x), x.min(0), x.max(0), losses, seed)


# ----------------------------------------------------------------------------- flight arrays, artifact

def flight_arrays(fit: GpFit) -> gpa.GpArrays:
    """The float64 model arrays of §6 from a trained SVGP (the flight float32 arrays derive from them)."""
    if fit.kind != "sparse":
        raise ValueError("flight arrays come from a sparse GP")
    model = fit.model
    base = model.variational_strategy.base_variational_strategy
    vd = base._variational_distribution
    R = vd.chol_variational_covar.detach().numpy()
    R = np.tril(R)
    jitter = base.jitter_val if base.jitter_val is not None else gpytorch.settings.variational_cholesky_jitter.value(
        np.float64)
    task_noise = fit.likelihood.task_noises.detach().numpy().reshape(3)
    return gpa.GpArrays(
        input_scale=INPUT_SCALES.copy(),
        output_scale=np.asarray(fit.output_scale, dtype=np.float64).copy(),
        lengthscale=model.covar_module.base_kernel.lengthscale.detach().numpy().reshape(9).astype(np.float64),
        outputscale=float(model.covar_module.outputscale.detach()),
        noise=task_noise.astype(np.float64),
        jitter=float(jitter),
        Z=base.inducing_points.detach().numpy().astype(np.float64).copy(),
        m=vd.variational_mean.detach().numpy().astype(np.float64).copy(),
        R=R.astype(np.float64),
    )


def artifact_from(fit: GpFit, metadata: dict | None = None, cond_max: float = gpa.COND_MAX) -> gpa.GpArtifact:
    """The sealed GP artifact (§7) of a trained SVGP."""
    meta = {"creator": "staregen host.learn.gp", "seed": fit.seed, "dataset_sha256": None, "test_mse": None,
            "train_time_s": round(fit.train_time_s, 3), "n_train": fit.n_train,
            "torch": torch.__version__, "gpytorch": gpytorch.__version__}
    meta.update(metadata or {})
    return gpa.GpArtifact(arrays=flight_arrays(fit), envelope_min=np.asarray(fit.x_min, dtype=np.float64),
                          envelope_max=np.asarray(fit.x_max, dtype=np.float64), cond_max=cond_max, metadata=meta)


# ----------------------------------------------------------------------------- synthetic data (tests, benchmark)

def synthetic(n: int, seed: int = 0, noise: float = 0.005) -> tuple[np.ndarray, np.ndarray]:
    """x drawn at the scale of §3 (q_v ~ 0.2, ω ~ 0.01 rad/s, ω̇ ~ 5e-4 rad/s²) and d = a smooth known
    map (a stiffness-like, a rate-cross and an inertia-like term, ~0.05-0.1 N·m) + Gaussian noise."""
    rng = np.random.default_rng(seed)
    x = rng.uniform(-1.0, 1.0, (n, 9)) * INPUT_SCALES
    q, w, wd = x[:, :3] / 0.2, x[:, 3:6] / 0.01, x[:, 6:] / 5e-4
    d = (-0.05 * np.sin(2.0 * q) - 0.02 * np.tanh(w) * np.roll(w, 1, axis=1)
         - 0.08 * wd + 0.01 * q * np.roll(w, 2, axis=1))
    return x, d + noise * rng.standard_normal(d.shape)
