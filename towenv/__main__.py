"""``python -m towenv``: the towenv command line."""
import sys

from .cli import main

sys.exit(main())
