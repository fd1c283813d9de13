"""Fixtures shared by every test folder (unit, verification, envs, agents, validation). Plain helpers are in
``tests/support/helpers.py`` (``from helpers import peer_deck``)."""
import os

import pytest

from helpers import peer_deck

try:        # hypothesis is a dev extra
    from hypothesis import settings as _hyp_settings
except ImportError:         # pragma: no cover
    _hyp_settings = None
if _hyp_settings is not None:
    # Fuzz tests draw the same examples on every run (CI included): a red CI is then reproducible, not a new
    # random draw. ``HYPOTHESIS_PROFILE=explore python -P -m pytest ...`` draws fresh random examples instead.
    _hyp_settings.register_profile("towenv", derandomize=True, database=None)
    _hyp_settings.register_profile("explore", derandomize=False)
    _hyp_settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "towenv"))


@pytest.fixture
def peer():
    return peer_deck
