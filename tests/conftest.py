"""Fixtures shared by every test folder (unit, verification, envs, agents, validation). Plain helpers are in
``tests/support/helpers.py`` (``from helpers import peer_deck``)."""
import pytest

from helpers import peer_deck


@pytest.fixture
def peer():
    return peer_deck
