"""Fixtures shared by all test modules (the toy systems themselves are in
``helpers.py``)."""

from __future__ import annotations

import pytest
from helpers import (
    brusselator,
    fold_normal_form,
    hopf_normal_form,
    pitchfork,
    transcritical,
)

from continuation.system import System


@pytest.fixture
def fold_system() -> System:
    return fold_normal_form()


@pytest.fixture
def hopf_system() -> System:
    return hopf_normal_form()


@pytest.fixture
def transcritical_system() -> System:
    return transcritical()


@pytest.fixture
def pitchfork_system() -> System:
    return pitchfork()


@pytest.fixture
def brusselator_system() -> System:
    return brusselator()
