"""Session set-up: the corpus must be there, Hypothesis keeps nothing in the repository."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import configuration, settings

import corpus

# No example database (replaying old failures is the regression files' job) and no deadline:
# a loaded CI machine makes any per-example time limit a flaky failure.
settings.register_profile("planefmt", database=None, deadline=None)
settings.load_profile("planefmt")
# Whatever Hypothesis still caches goes under the system's temporary folder, not the working tree.
configuration.set_hypothesis_home_dir(Path(tempfile.gettempdir()) / "planefmt-hypothesis")


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "slow: minutes per case; `make test-slow` runs them, `make test` does not")


def pytest_sessionstart(session: pytest.Session) -> None:
    why = corpus.problem()
    if why is not None:
        pytest.exit(why, returncode=pytest.ExitCode.USAGE_ERROR)
