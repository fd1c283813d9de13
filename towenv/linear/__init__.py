"""Linearised frequency-domain model of the tow (Hover et al. 1994): RAOs, spectral statistics and
passive-compensator tuning in milliseconds. See :mod:`towenv.linear.model` and docs/linear.md."""
from .model import (CompensatorTuning, LinearisationError, LinearModel, LinearResponse, Outputs, SpectralResult,
                    OUTPUT_DOC)

__all__ = ["LinearModel", "LinearResponse", "SpectralResult", "CompensatorTuning", "LinearisationError",
           "Outputs", "OUTPUT_DOC"]
