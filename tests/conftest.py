"""Shared test set-up: the library on the path (also without an editable install), the session's smoke run, and
how ``pytest -n`` (pytest-xdist: ``make test``) shares the tests among its workers."""
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import natscene  # noqa: E402,F401  (exports DRJIT_LIBLLVM_PATH before anything imports drjit)


@pytest.fixture(scope="session")
def smoke_run(tmp_path_factory):
    """(repo copy, workdir, process) of one finished run of the smoke workflow (tests/smoke.py), shared by the
    workflow and rerun tests; a test that edits the copy or the run restores them."""
    from smoke import start
    return start(tmp_path_factory.mktemp("smoke"))


#: tests that one worker runs, in order, as a whole (pytest-xdist's scopes): by module (its module fixtures made
#: once), the modules of the smoke run together (``smoke_run``, made once); the modules in :data:`SPREAD` share
#: nothing and spread over the workers case by case
SMOKE_RUN = ("test_reruns", "test_workflow")
SPREAD = ("test_slab",)
#: the longest scopes (minutes each on 2 cores), started first so that the short ones fill the workers' ends
LONGEST = ("smoke_run", "test_transport", "test_thick", "test_bad_inputs", "test_frames")


def _module(nodeid: str) -> str:
    return nodeid.split("::", 1)[0].rsplit("/", 1)[-1].removesuffix(".py")


def scope(nodeid: str) -> str:
    """The scope a test belongs to (above)."""
    module = _module(nodeid)
    return "smoke_run" if module in SMOKE_RUN else nodeid if module in SPREAD else module


def pytest_collection_modifyitems(config, items):
    """The longest scopes first (:data:`LONGEST`), then the cases of :data:`SPREAD` by their thickness ``tau``,
    thickest first (minutes each at 300, seconds at 1), then the rest in their order."""
    rank = {g: i for i, g in enumerate(LONGEST)}

    def key(item):
        spread = _module(item.nodeid) in SPREAD and hasattr(item, "callspec")
        return rank.get(scope(item.nodeid), len(LONGEST)), -float(item.callspec.params.get("tau", 0.0)) if spread else 0.0
    items.sort(key=key)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``pytest -n`` sends each worker whole scopes (:func:`scope`; pytest-xdist's own ``xdist_group`` marks are
    not read under pytest 9.2, which keeps a test's id elsewhere than xdist writes the group)."""
    from xdist.scheduler import LoadScopeScheduling
    config.option.loadscopereorder = False      # the order above, not xdist's (the scopes with most tests first)

    class ByScope(LoadScopeScheduling):
        def _split_scope(self, nodeid):
            return scope(nodeid)

    return ByScope(config, log)
