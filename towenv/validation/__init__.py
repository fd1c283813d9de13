"""Validation against published cases (issue 6): the thesis's Chapter 4 examples and channel runs, Hover et
al.'s deep tow and compensator study, Srivastava et al.'s towed-array manoeuvres and the full-scale trials.

    python scripts/validate.py            # full report -> docs/validation.md (+ figures, results cache)
    python scripts/validate.py --quick    # the CI version
    python -m towenv.validation --cases hover

See :mod:`towenv.validation.cases` for the case functions and :mod:`towenv.validation.report` for the report.
"""
from .cases import (ALL, channel_runs, full_scale_trials, hover_deep_tow, simulator_problems,  # noqa: F401
                    srivastava_array, thesis_chapter4)
from .report import main, render, run_cases  # noqa: F401
