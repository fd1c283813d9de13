"""Baseline controllers, SB3 training helpers and evaluation reports for the towenv environments.

Layout
------
* :mod:`agents.common`     — observation decoding (named channels in physical units), sea-state keys.
* :mod:`agents.baselines`  — baseline controllers with an SB3-like ``predict``:
  ``locked``, ``default_passive``, ``best_passive``, ``hover`` (``towenv/CompensatorGains-v0``) and
  ``fixed_winch``, ``pd_ff``, ``constant_tension`` (``towenv/WinchPayout-v0``).
* :mod:`agents.tuning`     — the grid searches that produce ``agents/hyperparams/baselines.yml``.
* :mod:`agents.zoo`        — rl-zoo style hyperparameter YAML, environment factories, the
  self-contained policy zip (SB3 model + VecNormalize statistics + metadata) and its loader.
* :mod:`agents.metrics`    — rollouts with common random numbers, per-episode metrics, bootstrap CIs.
* :mod:`agents.report`     — the Markdown/PNG/HTML evaluation report.

* :mod:`agents.ars`        — ARS (random search) on a linear residual over the along-cable winch law, with the
  MRU along-cable history as features; its policy file (.npz) and loader.
* :mod:`agents.train`, :mod:`agents.evaluate` — the training and evaluation command lines
  (``python -m agents.train`` = ``python scripts/train.py``; same for evaluate).

``agents`` is installed next to ``towenv`` (``pip install ".[rl]"``; its tuned tables, hyperparameter YAMLs
and the committed policies ``agents/trained/*.zip``, ``*.npz`` are package data), so ``import agents`` works from any
folder. ``import agents`` itself is light; the modules that need torch/stable-baselines3 import them when used.
"""
from __future__ import annotations

__all__ = ["BASELINES", "make_baseline", "load_policy", "baseline_names"]


def __getattr__(name):
    if name in ("BASELINES", "make_baseline", "baseline_names"):
        from . import baselines
        return getattr(baselines, name)
    if name == "load_policy":
        from .zoo import load_policy
        return load_policy
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
