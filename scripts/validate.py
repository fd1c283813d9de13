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

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from towenv.validation.report import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
