"""The validation cases, one function each. Every function takes ``quick`` (short runs and few variants for
CI) and an output folder for its figures, and returns a dict with the case's ``inputs``, ``assumptions``,
``tables``, ``figures``, ``findings``, ``claims`` (each with ``holds`` and its evidence), ``disagreements``
and the raw ``values`` behind them. The implementations live in the modules named below."""
from __future__ import annotations

from pathlib import Path

from . import channel, hover, problems, srivastava, thesis, trials
from .common import CaseContext

__all__ = ["thesis_chapter4", "channel_runs", "hover_deep_tow", "srivastava_array", "full_scale_trials",
           "simulator_problems", "ALL"]


def _ctx(quick, outdir, progress):
    return CaseContext(quick=quick, outdir=Path(outdir), progress=progress)


def thesis_chapter4(quick: bool = False, outdir=Path("docs/validation"), progress: bool = False) -> dict:
    """Case 1: thesis Tables 4.1–4.3 — conventional vs two-part tows, the turn, series/parallel multi-tows."""
    return thesis.run(_ctx(quick, outdir, progress))


def channel_runs(quick: bool = False, outdir=Path("docs/validation"), progress: bool = False) -> dict:
    """Case 2: channel runs I31, C31, YA22 with estimated body data and the sensitivity to every estimate."""
    return channel.run(_ctx(quick, outdir, progress))


def hover_deep_tow(quick: bool = False, outdir=Path("docs/validation"), progress: bool = False) -> dict:
    """Case 3: Hover et al. deep tow frequency response, compensator study, S-shaped tether."""
    return hover.run(_ctx(quick, outdir, progress))


def srivastava_array(quick: bool = False, outdir=Path("docs/validation"), progress: bool = False) -> dict:
    """Case 4: Srivastava et al. towed array speed manoeuvres with and without current."""
    return srivastava.run(_ctx(quick, outdir, progress))


def full_scale_trials(quick: bool = False, outdir=Path("docs/validation"), progress: bool = False) -> dict:
    """Case 5: the thesis's full-scale trials, single vs two-part tow, as far as the inputs allow."""
    return trials.run(_ctx(quick, outdir, progress))


def simulator_problems(hover_values: dict | None = None, outdir=Path("docs/validation")) -> dict:
    """Minimal reproductions of the simulator problems found while validating."""
    return problems.run(_ctx(True, outdir, False), hover_values)


ALL = {"thesis": thesis_chapter4, "channel": channel_runs, "hover": hover_deep_tow,
       "srivastava": srivastava_array, "trials": full_scale_trials}
