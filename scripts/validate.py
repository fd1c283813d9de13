#!/usr/bin/env python
"""Run every validation case and write docs/validation.md with its figures (docs/validation/*.png) and the
result cache (docs/validation/results.json).

    python scripts/validate.py                      # full report (the committed one)
    python scripts/validate.py --quick              # CI version, written to out/validation_quick/
    python scripts/validate.py --cases hover thesis # some cases (merged into the cached full report)
    python scripts/validate.py --report-only        # re-render the Markdown from the cache, no simulation
"""
import sys
from pathlib import Path

from towenv.validation.report import main

REPO = Path(__file__).resolve().parents[1]

if __name__ == "__main__":
    argv = sys.argv[1:]
    if "--out" not in argv and "-h" not in argv and "--help" not in argv:
        # this repository's script refreshes the committed report; `towenv validate` writes under ./out/
        argv += ["--out", str(REPO / ("out/validation_quick" if "--quick" in argv else "docs"))]
    sys.exit(main(argv))
