"""Training of the 12-H-3 network on optimal-control samples (paper 001 section 6), exported as an artifact.

The flow of `train_artifact`:
  1. the usable samples (host.learn.samples.load_dataset), checked: finite, enough of them;
  2. a seeded 75/25 split (paper 6.1);
  3. MATLAB mapminmax settings from the TRAINING set only (codegen.artifact.mapminmax_settings:
     the float32 xoffset/gain the flight C applies, so training sees exactly the flight map);
  4. a torch float64 net 12-H-3, hidden activation (tansig = tanh by default), linear output,
     trained with a recipe: `paper` (SGD with momentum, dropout 0.1, weight decay 0.01) or
     `default` (full-batch Adam warm start, then L-BFGS);
  5. test metrics (eq. 24 sum and means, normalised and physical, relative torque error) for the
     exported net and for the two baselines of host.control.baselines fitted on the same split;
  6. the artifact (codegen.artifact.from_torch), whose metadata records the data hash, the recipe,
     the split, the metrics and, from a sweep, the choice. It holds no timing, so the same seed and
     data give the same bytes.

Torch runs on one thread: a 12-40-3 net trains ~60x slower with several threads on this machine,
and one thread makes the result independent of the caller's thread setting.
"""
from __future__ import annotations

import hashlib
import math
import os
import tempfile
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from codegen import artifact as art
from codegen import atomic
from codegen.units.network import reference
from host.control.baselines import LinearLS, SaturatedLinear, baselines_document
from host.errors import HostError

TRAIN_FRACTION = 0.75
N_IN, N_OUT = 12, 3
DEFAULT_HIDDEN = 40
EXPORTABLE_ACTIVATION = "tansig"  # the only hidden activation the artifact and the flight C implement

# MATLAB transfer-function names -> what the torch net uses.
ACTIVATIONS = {
    "tansig": "tanh: MATLAB tansig(n) = 2/(1+exp(-2n)) - 1, identical to tanh",
    "logsig": "logistic: MATLAB logsig(n) = 1/(1+exp(-n))",
    "sigmoid": ("Elliot sigmoid n/(1+|n|) (MATLAB elliotsig): MATLAB has no transfer function named "
                "'sigmoid', and its sigmoidLayer is the logistic, i.e. logsig again"),
    "relu": "max(0, n): MATLAB poslin / reluLayer",
}

TEST_MSE_DEFINITION = ("mean over the 3 x N_test test elements of the squared error in mapminmax-normalised "
                       "units (eq. 24 divided by 3 N_test)")
RELATIVE_ERROR_DEFINITION = "||M_net - M_ocp||_F / ||M_ocp||_F over all test samples and the 3 axes (N·m)"


# ----------------------------------------------------------------------------- recipes

@dataclass(frozen=True)
class Recipe:
    """How a net is trained. `epochs`: SGD passes over the training set (paper) or L-BFGS
    iterations after the Adam warm start (default; each iteration is one or more full-batch passes)."""

    name: str
    epochs: int
    optimiser: str              # "sgdm" or "adam+lbfgs"
    learning_rate: float
    batch_size: int | None      # None: full batch
    momentum: float = 0.0
    dropout: float = 0.0        # after the hidden activation; identity at export
    weight_decay: float = 0.0   # L2 on the weights only (MATLAB: BiasL2Factor 0)
    adam_steps: int = 0
    loss: str = "mse"           # "mse": mean over outputs and samples; "half-sse": MATLAB regressionLayer
    init: str = "glorot uniform weights, zero biases (MATLAB trainNetwork's fullyConnectedLayer default)"


# MATLAB trainNetwork's sgdm defaults (learning rate 0.01, momentum 0.9, mini-batch 128) with the
# paper's dropout 0.1 and L2 0.01 and Table 4's 700 epochs; MATLAB's regression loss is half the
# sum over outputs of the squared error, averaged over the batch, which weighs the data 1.5x more
# against the L2 term than a plain mean.
PAPER_RECIPE = Recipe(name="paper", epochs=700, optimiser="sgdm", learning_rate=0.01, batch_size=128,
                      momentum=0.9, dropout=0.1, weight_decay=0.01, loss="half-sse")
DEFAULT_RECIPE = Recipe(name="default", epochs=1000, optimiser="adam+lbfgs", learning_rate=0.01,
                        batch_size=None, adam_steps=300)
RECIPES = {r.name: r for r in (DEFAULT_RECIPE, PAPER_RECIPE)}
LBFGS_HISTORY = 50


def recipe_named(name: str, epochs: int | None = None) -> Recipe:
    if name not in RECIPES:
        raise HostError(f"unknown recipe {name!r}; choose one of {', '.join(RECIPES)}")
    recipe = RECIPES[name]
    if epochs is not None:
        if epochs <= 0:
            raise HostError(f"the number of epochs must be > 0, got {epochs}")
        recipe = replace(recipe, epochs=int(epochs))
    return recipe


# ----------------------------------------------------------------------------- data, split, normalisation

def n_parameters(hidden: int, n_in: int = N_IN, n_out: int = N_OUT) -> int:
    return hidden * (n_in + 1) + n_out * (hidden + 1)


def minimum_samples(hidden: int = DEFAULT_HIDDEN) -> int:
    """Fewest usable samples accepted: the training set must hold at least as many samples as the
    net has parameters (643 for 12-40-3, so 858 samples), or it can interpolate them."""
    return math.ceil(n_parameters(hidden) / TRAIN_FRACTION)


def check_samples(X: np.ndarray, Y: np.ndarray, hidden: int) -> tuple[np.ndarray, np.ndarray]:
    X = np.ascontiguousarray(X, dtype=np.float64)
    Y = np.ascontiguousarray(Y, dtype=np.float64)
    if X.ndim != 2 or X.shape[1] != N_IN or Y.ndim != 2 or Y.shape[1] != N_OUT or len(X) != len(Y):
        raise HostError(f"training data must be X (m, {N_IN}) and Y (m, {N_OUT}), got {X.shape} and {Y.shape}")
    if not (np.isfinite(X).all() and np.isfinite(Y).all()):
        raise HostError("training data contain non-finite values")
    need = minimum_samples(hidden)
    if len(X) < need:
        raise HostError(f"{len(X)} usable samples, fewer than the {need} needed to train a "
                        f"{N_IN}-{hidden}-{N_OUT} net (the 75 % training split must hold at least its "
                        f"{n_parameters(hidden)} parameters)")
    return X, Y


def dataset_sha256(X: np.ndarray, Y: np.ndarray) -> str:
    """sha256 of the used samples: X then Y, float64 little-endian, row-major."""
    h = hashlib.sha256()
    for a in (X, Y):
        h.update(np.ascontiguousarray(a, dtype="<f8").tobytes())
    return h.hexdigest()


def split_indices(n: int, seed: int, train_fraction: float = TRAIN_FRACTION) -> tuple[np.ndarray, np.ndarray]:
    """Seeded random split (paper 6.1): sorted train and test row indices, round(0.75 n) for training."""
    order = np.random.default_rng(seed).permutation(n)
    n_train = int(round(train_fraction * n))
    return np.sort(order[:n_train]), np.sort(order[n_train:])


def mapminmax_apply(m: art.MapMinMax, x: np.ndarray) -> np.ndarray:
    """MATLAB mapminmax 'apply' in float64 with the artifact's settings: (x - xoffset)·gain + ymin."""
    return (x - m.xoffset.astype(np.float64)) * m.gain.astype(np.float64) + float(m.ymin)


def mapminmax_reverse(m: art.MapMinMax, y: np.ndarray) -> np.ndarray:
    """MATLAB mapminmax 'reverse': (y - ymin)/gain + xoffset."""
    return (y - float(m.ymin)) / m.gain.astype(np.float64) + m.xoffset.astype(np.float64)


@dataclass(frozen=True)
class Split:
    """The split data, raw and normalised with the training set's mapminmax settings."""

    X_train: np.ndarray
    Y_train: np.ndarray
    X_test: np.ndarray
    Y_test: np.ndarray
    input_map: art.MapMinMax
    output_map: art.MapMinMax
    seed: int

    @property
    def xn_train(self) -> np.ndarray:
        return mapminmax_apply(self.input_map, self.X_train)

    @property
    def yn_train(self) -> np.ndarray:
        return mapminmax_apply(self.output_map, self.Y_train)

    @property
    def xn_test(self) -> np.ndarray:
        return mapminmax_apply(self.input_map, self.X_test)


def make_split(X: np.ndarray, Y: np.ndarray, seed: int) -> Split:
    train, test = split_indices(len(X), seed)
    Xtr, Ytr = X[train], Y[train]
    return Split(Xtr, Ytr, X[test], Y[test],
                 input_map=art.mapminmax_settings(Xtr.min(axis=0), Xtr.max(axis=0)),
                 output_map=art.mapminmax_settings(Ytr.min(axis=0), Ytr.max(axis=0)), seed=seed)


# ----------------------------------------------------------------------------- metrics

def error_metrics(Y_true: np.ndarray, Y_pred: np.ndarray, output_map: art.MapMinMax) -> dict:
    """Test-set errors: eq. 24 (a sum, normalised), means normalised and physical, relative error."""
    err_n = mapminmax_apply(output_map, Y_pred) - mapminmax_apply(output_map, Y_true)
    err = Y_pred - Y_true
    return {
        "n_test": int(len(Y_true)),
        "mse_eq24_sum_normalised": float(np.sum(err_n ** 2)),
        "mse_mean_normalised": float(np.mean(err_n ** 2)),
        "mse_mean_physical_Nm2": float(np.mean(err ** 2)),
        "rmse_per_axis_Nm": [float(v) for v in np.sqrt(np.mean(err ** 2, axis=0))],
        "max_abs_error_Nm": float(np.max(np.abs(err))),
        "relative_torque_error": float(np.linalg.norm(err) / np.linalg.norm(Y_true)),
    }


# ----------------------------------------------------------------------------- torch nets

def _torch():
    import torch

    torch.set_num_threads(1)  # several threads make this small net ~60x slower here, and vary results
    return torch


def _elliotsig():
    """MATLAB elliotsig n/(1+|n|) as a torch module (defined here so torch is imported on use only)."""
    torch = _torch()

    class ElliotSig(torch.nn.Module):
        def forward(self, x):
            return x / (1 + x.abs())

    return ElliotSig()


def activation_module(name: str):
    torch = _torch()
    makers = {"tansig": torch.nn.Tanh, "logsig": torch.nn.Sigmoid, "sigmoid": _elliotsig,
              "relu": torch.nn.ReLU}
    if name not in makers:
        raise HostError(f"unknown activation {name!r}; choose one of {', '.join(ACTIVATIONS)}")
    return makers[name]()


def build_net(activation: str, hidden: int, dropout: float):
    """float64 nn.Sequential(Linear(12, H), act, [Dropout], Linear(H, 3)), Glorot-initialised."""
    torch = _torch()
    layers = [torch.nn.Linear(N_IN, hidden), activation_module(activation)]
    if dropout > 0:
        layers.append(torch.nn.Dropout(dropout))
    layers.append(torch.nn.Linear(hidden, N_OUT))
    net = torch.nn.Sequential(*layers).double()
    for layer in (layers[0], layers[-1]):
        torch.nn.init.xavier_uniform_(layer.weight)
        torch.nn.init.zeros_(layer.bias)
    return net


def _linear_layers(net):
    torch = _torch()
    return [m for m in net if isinstance(m, torch.nn.Linear)]


def _mse(net, x, y):
    return ((net(x) - y) ** 2).mean()


def _loss(recipe: Recipe, net, x, y):
    if recipe.loss == "half-sse":
        return 0.5 * ((net(x) - y) ** 2).sum(dim=1).mean()
    return _mse(net, x, y)


def _train_sgdm(net, x, y, recipe: Recipe, generator) -> None:
    """Mini-batch SGD with momentum; L2 on the weights only; reshuffled every epoch."""
    torch = _torch()
    first, last = _linear_layers(net)
    opt = torch.optim.SGD([{"params": [first.weight, last.weight], "weight_decay": recipe.weight_decay},
                           {"params": [first.bias, last.bias], "weight_decay": 0.0}],
                          lr=recipe.learning_rate, momentum=recipe.momentum)
    n = x.shape[0]
    batch = recipe.batch_size or n
    for _ in range(recipe.epochs):
        order = torch.randperm(n, generator=generator)
        for start in range(0, n, batch):
            rows = order[start:start + batch]
            opt.zero_grad()
            _loss(recipe, net, x[rows], y[rows]).backward()
            opt.step()


def _train_adam_lbfgs(net, x, y, recipe: Recipe) -> None:
    """Full batch: Adam (cosine-annealed) to leave the initial plateau, then L-BFGS to converge."""
    torch = _torch()
    opt = torch.optim.Adam(net.parameters(), lr=recipe.learning_rate)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, max(recipe.adam_steps, 1))
    for _ in range(recipe.adam_steps):
        opt.zero_grad()
        _loss(recipe, net, x, y).backward()
        opt.step()
        sched.step()
    lbfgs = torch.optim.LBFGS(net.parameters(), lr=1.0, max_iter=recipe.epochs, history_size=LBFGS_HISTORY,
                              line_search_fn="strong_wolfe", tolerance_grad=1e-12, tolerance_change=1e-16)

    def closure():
        lbfgs.zero_grad()
        loss = _loss(recipe, net, x, y)
        loss.backward()
        return loss

    lbfgs.step(closure)


@dataclass
class FitResult:
    net: object                 # the trained float64 torch net, in eval mode
    activation: str
    hidden: int
    recipe: Recipe
    seed: int
    train_seconds: float
    train_mse_normalised: float


def fit_network(split: Split, activation: str = EXPORTABLE_ACTIVATION, hidden: int = DEFAULT_HIDDEN,
                recipe: Recipe = DEFAULT_RECIPE, seed: int = 0) -> FitResult:
    """Train one net on the split's normalised training set; deterministic for a seed (1 thread)."""
    torch = _torch()
    if hidden <= 0:
        raise HostError(f"the hidden layer size must be > 0, got {hidden}")
    x = torch.from_numpy(split.xn_train)
    y = torch.from_numpy(split.yn_train)
    start = time.perf_counter()
    with torch.random.fork_rng(devices=[]):  # seeds init and dropout without touching the caller's RNG
        torch.manual_seed(seed)
        net = build_net(activation, hidden, recipe.dropout)
        net.train()
        if recipe.optimiser == "sgdm":
            _train_sgdm(net, x, y, recipe, torch.Generator().manual_seed(seed))
        elif recipe.optimiser == "adam+lbfgs":
            _train_adam_lbfgs(net, x, y, recipe)
        else:
            raise HostError(f"unknown optimiser {recipe.optimiser!r}")
    net.eval()
    with torch.no_grad():
        loss = float(_mse(net, x, y))
    if not math.isfinite(loss):
        raise HostError(f"training diverged (training MSE {loss}); try the default recipe or fewer epochs")
    return FitResult(net, activation, hidden, recipe, seed, time.perf_counter() - start, loss)


def predict_physical(fit: FitResult, split: Split, X: np.ndarray) -> np.ndarray:
    """The float64 torch net on raw inputs (N·m), through the split's mapminmax settings."""
    torch = _torch()
    with torch.no_grad():
        yn = fit.net(torch.from_numpy(mapminmax_apply(split.input_map, X))).numpy()
    return mapminmax_reverse(split.output_map, yn)


def exportable_net(fit: FitResult):
    """nn.Sequential(Linear, Tanh, Linear) of a tansig fit (dropout dropped: identity at inference)."""
    torch = _torch()
    if fit.activation != EXPORTABLE_ACTIVATION:
        raise HostError(f"only a {EXPORTABLE_ACTIVATION} net can be exported to flight C, not {fit.activation}")
    first, last = _linear_layers(fit.net)
    return torch.nn.Sequential(first, torch.nn.Tanh(), last)


# ----------------------------------------------------------------------------- the training stage

@dataclass
class TrainReport:
    """What a training run measured; `metadata()` is the timing-free part stored in the artifact."""

    activation: str
    hidden: int
    recipe: dict
    seed: int
    n_train: int
    n_test: int
    dataset: dict
    dataset_sha256: str
    net: dict                   # test metrics of the exported net (its float32 weights, float64 arithmetic)
    baselines: dict             # name -> test metrics
    train_mse_normalised: float
    train_seconds: float        # the net's optimisation only
    total_seconds: float = 0.0  # load, split, baselines, training, export
    choice: dict | None = None  # from a sweep: the grid, the overall best and the exported tansig
    # the fitted baselines as a baselines file (host.control.baselines), to fly them; not metadata
    baseline_laws: dict = field(default_factory=dict)

    def metadata(self) -> dict:
        meta = {k: v for k, v in asdict(self).items() if k not in ("train_seconds", "total_seconds", "baseline_laws")}
        meta.update(creator="staregen train (host.learn.training)", test_mse=self.net["mse_mean_normalised"],
                    test_mse_definition=TEST_MSE_DEFINITION,
                    relative_torque_error_definition=RELATIVE_ERROR_DEFINITION,
                    network={"sizes": [N_IN, self.hidden, N_OUT], "activations": [self.activation, "purelin"]},
                    split={"train_fraction": TRAIN_FRACTION, "seed": self.seed, "n_train": self.n_train,
                           "n_test": self.n_test, "normalisation": "mapminmax to [-1, 1] from the training set"})
        return meta

    def table_rows(self) -> list[tuple[str, dict]]:
        return [(f"net {N_IN}-{self.hidden}-{N_OUT} {self.activation} ({self.recipe['name']} recipe)", self.net)] + \
            list(self.baselines.items())

    def markdown_table(self) -> str:
        head = ("| model | eq. 24 sum (normalised) | MSE mean normalised | MSE mean [N·m²] | "
                "relative torque error | max abs error [N·m] |\n|---|---|---|---|---|---|")
        rows = [f"| {name} | {m['mse_eq24_sum_normalised']:.4g} | {m['mse_mean_normalised']:.4g} | "
                f"{m['mse_mean_physical_Nm2']:.4g} | {100 * m['relative_torque_error']:.3f} % | "
                f"{m['max_abs_error_Nm']:.3g} |" for name, m in self.table_rows()]
        return "\n".join([head, *rows])

    def summary(self) -> str:
        lines = [f"trained {N_IN}-{self.hidden}-{N_OUT} {self.activation} with the {self.recipe['name']} recipe "
                 f"({self.recipe['epochs']} epochs, seed {self.seed}) on {self.n_train} samples, tested on "
                 f"{self.n_test} ({self.dataset.get('objective', 'given data')}); training {self.train_seconds:.1f} s, "
                 f"whole stage {self.total_seconds:.1f} s",
                 self.markdown_table(),
                 f"relative torque error = {RELATIVE_ERROR_DEFINITION}"]
        return "\n".join(lines)


def _dataset_summary(report: dict | None) -> dict:
    """The dataset facts worth keeping in the artifact (no folder path: the bytes must not depend on it)."""
    keys = ("objective", "config_hash", "n_total", "n_used", "n_excluded", "excluded_by_status", "rule", "ocp")
    return {k: report[k] for k in keys if report and k in report}


def load_training_data(data) -> tuple[np.ndarray, np.ndarray, dict]:
    """A dataset folder (host.learn.samples.load_dataset, usable rows only) or an (X, Y, report) tuple."""
    if isinstance(data, (str, os.PathLike)):
        from host.learn.samples import load_dataset

        X, Y, _, report = load_dataset(data)
        return X, Y, report
    X, Y, report = data
    return X, Y, dict(report or {})


def torque_bound_of(report: dict) -> float | None:
    return (report.get("ocp") or {}).get("torque_bound")


def fit_baselines(split: Split, bound: float | None) -> tuple[dict, tuple[LinearLS, SaturatedLinear]]:
    """Test metrics of the two baselines (name -> metrics) and the fitted laws themselves."""
    linear = LinearLS.fit(split.X_train, split.Y_train)
    saturated = SaturatedLinear.fit(split.X_train, split.Y_train, bound)
    metrics = {model.name: error_metrics(split.Y_test, model.predict(split.X_test), split.output_map)
               for model in (linear, saturated)}
    return metrics, (linear, saturated)


def export(fit: FitResult, split: Split, metadata: dict | None = None) -> art.Artifact:
    return art.from_torch(exportable_net(fit), split.input_map.xmin, split.input_map.xmax,
                          split.output_map.xmin, split.output_map.xmax, metadata=metadata)


def check_writable(path) -> Path:
    """Fail before training if `path` cannot be written: its folder must exist and accept a file."""
    path = Path(path)
    if path.is_dir():
        raise HostError(f"{path}: is a folder; give the artifact's file name")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise HostError(f"{path}: cannot write the artifact, folder {parent} does not exist")
    try:
        with tempfile.NamedTemporaryFile(dir=parent, prefix=f".{path.name}.", suffix=".probe"):
            pass
    except OSError as exc:
        raise HostError(f"{path}: cannot write the artifact ({exc.strerror or exc})") from None
    return path


def baselines_path(artifact_path) -> Path:
    """Where the fitted baselines of an artifact go: network.json -> network.baselines.json."""
    p = Path(artifact_path)
    return p.with_name(f"{p.stem}.baselines.json")


def save_baselines(report: TrainReport, artifact_path) -> Path:
    """The fitted baselines next to the artifact (atomic), so that `simulate --controller
    pdff|linear --baselines FILE` can fly them."""
    path = baselines_path(artifact_path)
    try:
        return atomic.write_json(path, report.baseline_laws)
    except OSError as exc:
        raise HostError(f"{path}: cannot write the baselines ({exc.strerror or exc})") from None


def save_artifact(artifact: art.Artifact, path) -> Path:
    try:
        return artifact.save(path)
    except OSError as exc:
        raise HostError(f"{path}: cannot write the artifact ({exc.strerror or exc})") from None


def train_artifact(data, recipe: str | Recipe = "default", seed: int = 0, epochs: int | None = None,
                   hidden: int = DEFAULT_HIDDEN, choice: dict | None = None) -> tuple[art.Artifact, TrainReport]:
    """Train the 12-H-3 tansig net on `data` and return its artifact and report.

    `data`: a dataset folder (host.learn.samples.load_dataset) or (X, Y, report) with X (m, 12) S_in in
    Table 2 units and Y (m, 3) N·m; `report` may be {} (then no torque bound for the saturated
    baseline). `recipe`: "default" | "paper" or a Recipe; `epochs` overrides its epoch count.
    Raises HostError on bad or too few data.
    """
    start = time.perf_counter()
    X, Y, dataset_report = load_training_data(data)
    X, Y = check_samples(X, Y, hidden)
    recipe = recipe if isinstance(recipe, Recipe) else recipe_named(recipe, epochs)
    split = make_split(X, Y, seed)
    fit = fit_network(split, EXPORTABLE_ACTIVATION, hidden, recipe, seed)
    baseline_metrics, baseline_models = fit_baselines(split, torque_bound_of(dataset_report))
    report = TrainReport(
        activation=EXPORTABLE_ACTIVATION, hidden=hidden, recipe=asdict(recipe), seed=seed,
        n_train=len(split.X_train), n_test=len(split.X_test), dataset=_dataset_summary(dataset_report),
        dataset_sha256=dataset_sha256(X, Y), net={}, baselines=baseline_metrics,
        train_mse_normalised=fit.train_mse_normalised, train_seconds=fit.train_seconds, choice=choice)
    report.baseline_laws = baselines_document(*baseline_models, report.dataset_sha256)
    # Metrics of what flies: the artifact's float32 weights (float64 arithmetic); filled in, then sealed.
    unsealed = export(fit, split)
    report.net = error_metrics(split.Y_test, reference.reference_eval64(unsealed, split.X_test), split.output_map)
    artifact = export(fit, split, report.metadata())
    report.total_seconds = time.perf_counter() - start
    return artifact, report
