"""Cross-check of two simulators flying the same controller object: staregen's own (host.sim.simulator)
and Basilisk (host.sim.basilisk), from the same initial state with the same noise draws.

Reported: per target J_A, J_ω of both and their relative differences; the largest difference of
the attitude-error histories (every plant step); over several targets the two means, the sampling
spread of a mean (standard error s/√N over the targets) and the difference of the means in units
of that spread. Tolerances (issue 28): J_A, J_ω within 2 % per target with errors off; the means
within their spread (|Δ mean| ≤ 1 standard error) with errors on.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from host.core.constants import DEG
from host.sim import plots
from host.sim.metrics import StaringMetrics
from host.sim.simulator import History

J_TOLERANCE = 0.02          # relative, per target (errors off)
SPREAD_TOLERANCE = 1.0      # |Δ mean| in standard errors of the mean (errors on)


@dataclass
class CrossCheck:
    staregen: list[StaringMetrics]
    basilisk: list[StaringMetrics]
    max_attitude_diff_deg: float    # max over targets and time of |ΔA_bd| (any axis)
    max_rate_diff_deg_s: float      # max over targets and time of |Δω_e| (any axis)

    def relative(self, key: str) -> np.ndarray:
        a = np.array([getattr(m, key) for m in self.staregen])
        b = np.array([getattr(m, key) for m in self.basilisk])
        return (b - a) / np.abs(a)

    def means(self, key: str) -> dict:
        a = np.array([getattr(m, key) for m in self.staregen])
        b = np.array([getattr(m, key) for m in self.basilisk])
        n = len(a)
        se = float(np.std(a, ddof=1) / np.sqrt(n)) if n > 1 else 0.0
        diff = float(abs(np.mean(b) - np.mean(a)))
        return {"staregen": float(np.mean(a)), "basilisk": float(np.mean(b)), "standard_error": se,
                "difference_in_standard_errors": diff / se if se > 0 else None, "difference": diff}

    def verdict(self) -> dict:
        worst = {k: float(np.max(np.abs(self.relative(k)))) for k in ("J_A", "J_w")}
        out = {"max_relative_difference": worst,
               "per_target_within_2_percent": bool(max(worst.values()) <= J_TOLERANCE)}
        if len(self.staregen) > 1:
            means = {k: self.means(k) for k in ("J_A", "J_w")}
            out["means"] = means
            out["means_within_spread"] = bool(all(
                m["difference"] == 0.0 if m["difference_in_standard_errors"] is None
                else m["difference_in_standard_errors"] <= SPREAD_TOLERANCE for m in means.values()))
        return out

    def document(self) -> dict:
        return {"targets": [{"staregen": {"J_A": a.J_A, "J_w": a.J_w}, "basilisk": {"J_A": b.J_A, "J_w": b.J_w}}
                            for a, b in zip(self.staregen, self.basilisk)],
                "max_attitude_diff_deg": self.max_attitude_diff_deg, "max_rate_diff_deg_s": self.max_rate_diff_deg_s,
                "tolerances": {"J_relative": J_TOLERANCE, "means_standard_errors": SPREAD_TOLERANCE},
                **self.verdict()}


def cross_check(staregen: list[History], basilisk: list[History], m_staregen: list[StaringMetrics],
                m_basilisk: list[StaringMetrics]) -> CrossCheck:
    att = max(float(np.max(np.abs(a.A_bd - b.A_bd))) for a, b in zip(staregen, basilisk)) / DEG
    rate = max(float(np.max(np.abs(a.omega_e - b.omega_e))) for a, b in zip(staregen, basilisk)) / DEG
    return CrossCheck(m_staregen, m_basilisk, att, rate)


def summary_lines(c: CrossCheck) -> list[str]:
    v = c.verdict()
    rel = v["max_relative_difference"]
    lines = [f"cross-check, Basilisk against staregen's simulator ({len(c.staregen)} target(s)):",
             f"  max |relative difference| J_A {rel['J_A']:.2e}, J_w {rel['J_w']:.2e} (tolerance {J_TOLERANCE:.0%}): "
             + ("within" if v["per_target_within_2_percent"] else "NOT within"),
             f"  max |d A_bd| {c.max_attitude_diff_deg:.2e} deg, max |d omega_e| {c.max_rate_diff_deg_s:.2e} deg/s"]
    if len(c.staregen) == 1:
        a, b = c.staregen[0], c.basilisk[0]
        lines.append(f"  J_A {a.J_A:.6e} / {b.J_A:.6e} deg, J_w {a.J_w:.6e} / {b.J_w:.6e} deg/s (staregen / Basilisk)")
    for key, m in v.get("means", {}).items():
        spread = "no spread" if m["difference_in_standard_errors"] is None else \
            f"difference {m['difference_in_standard_errors']:.3f} standard errors"
        lines.append(f"  mean {key} {m['staregen']:.6e} / {m['basilisk']:.6e} (staregen / Basilisk), standard error "
                     f"{m['standard_error']:.2e}: {spread}")
    if "means_within_spread" in v:
        lines.append("  means " + ("within" if v["means_within_spread"] else "NOT within") + " their spread")
    return lines


def plot_overlay(t, series: list[tuple[str, np.ndarray, np.ndarray]], path, title: str) -> None:
    """Each (ylabel, staregen values (n, k), Basilisk values (n, k)): both runs overlaid, and below
    each pair their difference."""
    def draw(axes):
        for row, (ylabel, a, b) in enumerate(series):
            top, bottom = axes[2 * row], axes[2 * row + 1]
            for i in range(a.shape[1]):
                top.plot(t, a[:, i], "-", color=f"C{i}", lw=1.0, label=f"staregen {i + 1}")
                top.plot(t, b[:, i], "--", color=f"C{i}", lw=1.0, label=f"Basilisk {i + 1}")
                bottom.plot(t, b[:, i] - a[:, i], color=f"C{i}", lw=0.8, label=f"{i + 1}")
            top.set_ylabel(ylabel)
            bottom.set_ylabel("Basilisk − staregen")
            top.legend(fontsize=7, ncol=3, loc="upper right")
        axes[0].set_title(title)
    plots.stacked_figure(path, draw, 2 * len(series))
